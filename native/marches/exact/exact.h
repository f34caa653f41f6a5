// The exact march's whole frame on the CPU (march_exact.cpp, with Embree):
// the `cpu` entry of its row (march.cpp); nothing else calls it.
#pragma once
#include "glint/image.h"
#include "glint/options.h"
#include "glint/stages.h"

namespace glint::cpu {

Image trace_exact(const TraceInputs& in, const TraceOptions& opt, int threads);

}  // namespace glint::cpu
