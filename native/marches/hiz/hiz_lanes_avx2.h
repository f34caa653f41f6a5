// Eight float lanes in a ymm register, for the files built with -mavx2 alone
// (hiz_base_avx2.cpp, hiz_planes_avx2.cpp, hiz_reuse_avx2.cpp,
// hiz_rays_avx2.cpp). Everything here lives in an anonymous namespace, so
// each of those files has its own copy and the linker is never handed an
// AVX2 function that the rest of the library, built for the baseline, could
// end up calling. Include it from nowhere else.
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

// finite() and texel_seen() of glint's headers, on the lanes: v - v == 0,
// and w > 0 with every channel finite (p: the four channels of a texel row).
__attribute__((always_inline)) inline VI finite(VF v) { return (v - v) == splat(0.0f); }
__attribute__((always_inline)) inline VI texel_seen(const VF p[4]) {
  return (p[3] > splat(0.0f)) & finite(p[0]) & finite(p[1]) & finite(p[2]) & finite(p[3]);
}

__attribute__((always_inline)) inline VF vabs(VF v) { return reinterpret_cast<VF>(reinterpret_cast<VI>(v) & 0x7fffffff); }

// Two 4x4 transposes, one per 128-bit half: rk holds texels k and k + 4,
// four floats each; c[j] gets channel j of texels 0 .. 7 in lane order.
__attribute__((always_inline)) inline void transpose_halves(__m256 r0, __m256 r1, __m256 r2, __m256 r3, VF c[4]) {
  const __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);
  const __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
  c[0] = reinterpret_cast<VF>(_mm256_shuffle_ps(t0, t2, 0x44));
  c[1] = reinterpret_cast<VF>(_mm256_shuffle_ps(t0, t2, 0xEE));
  c[2] = reinterpret_cast<VF>(_mm256_shuffle_ps(t1, t3, 0x44));
  c[3] = reinterpret_cast<VF>(_mm256_shuffle_ps(t1, t3, 0xEE));
}

// Texels x .. x + 7 of an RGBA row as four vectors, one per channel.
__attribute__((always_inline)) inline void load_channels(const float* row, int x, VF c[4]) {
  const float* p = row + static_cast<size_t>(x) * 4;
  transpose_halves(_mm256_loadu2_m128(p + 16, p), _mm256_loadu2_m128(p + 20, p + 4),
                   _mm256_loadu2_m128(p + 24, p + 8), _mm256_loadu2_m128(p + 28, p + 12), c);
}

// The same for texels x .. x + 7 of an xyz row (3 floats a texel): each
// texel's 4-float load takes the next texel's first float as its fourth,
// which c[3] holds and nobody reads; the last texel's load is masked to
// three floats, so that the image's last texel reads nothing past it.
__attribute__((always_inline)) inline void load_xyz_channels(const float* row, int x, VF c[4]) {
  const float* p = row + static_cast<size_t>(x) * 3;
  const __m128 last = _mm_maskload_ps(p + 21, _mm_setr_epi32(-1, -1, -1, 0));
  transpose_halves(_mm256_loadu2_m128(p + 12, p), _mm256_loadu2_m128(p + 15, p + 3),
                   _mm256_loadu2_m128(p + 18, p + 6),
                   _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p + 9)), last, 1), c);
}

// The seen bytes of texels x .. x + 7 as lane masks; none where the row is
// off the image (seen null).
__attribute__((always_inline)) inline VI seen_mask(const unsigned char* seen, int x) {
  if (!seen) return VI{};
  const __m256i v = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(seen + x)));
  return reinterpret_cast<VI>(v) != VI{};
}

}  // namespace
}  // namespace glint::cpu
