// Eight float lanes in a ymm register, for the files built with -mavx2 alone
// (hiz_base_avx2.cpp, hiz_planes_avx2.cpp). Everything here lives in an
// anonymous namespace, so each of those files has its own copy and the
// linker is never handed an AVX2 function that the rest of the library,
// built for the baseline, could end up calling. Include it from nowhere else.
#pragma once
#include <immintrin.h>

#if !defined(__AVX2__)
#error "hiz_lanes_avx2.h is for the files built with -mavx2"
#endif

namespace glint::cpu {
namespace {

typedef float VF __attribute__((vector_size(32)));
typedef int VI __attribute__((vector_size(32)));

__attribute__((always_inline)) inline VF splat(float v) { return VF{v, v, v, v, v, v, v, v}; }
// Lane k of a where mask m is set, else of b.
__attribute__((always_inline)) inline VF pick(VI m, VF a, VF b) {
  return reinterpret_cast<VF>(
      _mm256_blendv_ps(reinterpret_cast<__m256>(b), reinterpret_cast<__m256>(a), reinterpret_cast<__m256>(m)));
}

}  // namespace
}  // namespace glint::cpu
