// One function per march: a whole frame on the CPU. These are the `cpu`
// entries of the table of marches (glint/marches.h); nothing else calls them.
#pragma once
#include "glint/image.h"
#include "glint/options.h"
#include "glint/stages.h"

namespace glint::cpu {

Image trace_exact(const TraceInputs& in, const TraceOptions& opt, int threads);

}  // namespace glint::cpu
