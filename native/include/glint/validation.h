// The checks every stage's inputs pass before it runs, whichever backend runs
// it (src/validation.cpp). Each throws InvalidArgument naming the argument as
// the Python keyword spells it.
#pragma once
#include "glint/backend.h"
#include "glint/image.h"
#include "glint/options.h"
#include "glint/projection.h"

namespace glint {

// Check a buffer's size and that it is non-empty; the name goes in the error.
void require_image(const Image& img, const char* name);
void require_same_size(const Image& a, const char* a_name, const Image& b, const char* b_name);
// Everything Backend::trace checks before it runs: buffer sizes, options, projection.
void require_trace_inputs(const TraceInputs& in, const TraceOptions& opt);
// What Backend::specular_weight and Backend::cone_blur check, on every backend.
void require_specular_weight_inputs(const Image& position, const Image& normal, const Image& specular,
                                    const Mat4& projection);
void require_cone_blur_inputs(const Image& color, const Image& uv, const Image& specular,
                              const MirrorScale* mirror);

// The checks every backend's reflection / combine make before they run.
void require_reflection_inputs(const Image& color, const Image* blurred, const Image& specular,
                               const Image* weight);
void require_combine_inputs(const Image& base, const Image& reflection, Combine mode,
                            const Image* specular_base, const Image* coverage);

}  // namespace glint
