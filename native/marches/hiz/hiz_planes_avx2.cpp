// The pyramid's plane normals (hiz_planes.cpp's plane_normal()) for x86-64
// CPUs with AVX2: eight texels of a row at once, one per lane. Like
// hiz_base_avx2.cpp, this file alone is built with -mavx2 and not -mfma and
// includes no inline functions but hiz_lanes_avx2.h's, private to it. Each
// lane does plane_normal()'s float operations in its order and picks between
// its branches with masks, so the normals are the scalar ones bit for bit
// (the tests compare the two pyramids).
//
// Why: the scalar rule is a chain of data-dependent branches per texel (which
// neighbours are seen, which side predicts the depth better), and at
// 1920x1080 it was about an eighth of a balanced trace on the CPU.
#include <immintrin.h>

#include "hiz_base.h"
#include "hiz_lanes_avx2.h"

namespace glint::cpu {
namespace {

__attribute__((always_inline)) inline VF vabs(VF v) { return reinterpret_cast<VF>(reinterpret_cast<VI>(v) & 0x7fffffff); }

// Texels x .. x + 7 of an RGBA row as four vectors, one per channel: two
// 4x4 transposes, one per 128-bit half (texels x .. x + 3 and x + 4 .. x + 7).
__attribute__((always_inline)) inline void load_channels(const float* row, int x, VF c[4]) {
  const float* p = row + static_cast<size_t>(x) * 4;
  __m256 r0 = _mm256_loadu2_m128(p + 16, p), r1 = _mm256_loadu2_m128(p + 20, p + 4);
  __m256 r2 = _mm256_loadu2_m128(p + 24, p + 8), r3 = _mm256_loadu2_m128(p + 28, p + 12);
  const __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);
  const __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
  c[0] = reinterpret_cast<VF>(_mm256_shuffle_ps(t0, t2, 0x44));
  c[1] = reinterpret_cast<VF>(_mm256_shuffle_ps(t0, t2, 0xEE));
  c[2] = reinterpret_cast<VF>(_mm256_shuffle_ps(t1, t3, 0x44));
  c[3] = reinterpret_cast<VF>(_mm256_shuffle_ps(t1, t3, 0xEE));
}

// The seen bytes of texels x .. x + 7 as lane masks; none where the row is off the image.
__attribute__((always_inline)) inline VI seen_mask(const unsigned char* seen, int x) {
  if (!seen) return VI{};
  const __m256i v = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(seen + x)));
  return reinterpret_cast<VI>(v) != VI{};
}

// A neighbour as axis_difference() sees it: its position (any value where
// it is not seen) and whether it is seen.
struct Side {
  VF p[3];
  VI seen;
};

// miss(): how far the depth this side predicts misses p's; a1 the adjacent
// texel, a2 the one beyond (its z only).
__attribute__((always_inline)) inline VF miss(VF pz, const Side& a1, VF a2z, VI a2_seen) {
  return pick(a2_seen, vabs((splat(2.0f) * a1.p[2] - a2z) - pz), vabs(a1.p[2] - pz));
}

// axis_difference() on the lanes: e, and whether either neighbour is seen.
__attribute__((always_inline)) inline VI axis_difference(const VF p[3], const Side& lo, VF lo2z, VI lo2_seen,
                                                         const Side& hi, VF hi2z, VI hi2_seen, VF e[3]) {
  const VI lower_better = lo.seen & hi.seen & (miss(p[2], lo, lo2z, lo2_seen) < miss(p[2], hi, hi2z, hi2_seen));
  const VI use_hi = hi.seen & ~lower_better;
  for (int k = 0; k < 3; ++k) e[k] = pick(use_hi, hi.p[k] - p[k], p[k] - lo.p[k]);
  return hi.seen | lo.seen;
}

}  // namespace

void hiz_plane_normals_row_avx2(const PlaneRow& r, int x_begin, int x_end) {
  const float* row = r.position[2];
  for (int x = x_begin; x + 8 <= x_end; x += 8) {
    VF c[4];
    VF p[3];
    load_channels(row, x, c);
    for (int k = 0; k < 3; ++k) p[k] = c[k];
    // Along x: the row's own texels at x - 2 .. x + 2.
    Side left, right;
    VF left2z, right2z;
    load_channels(row, x - 1, c);
    for (int k = 0; k < 3; ++k) left.p[k] = c[k];
    load_channels(row, x + 1, c);
    for (int k = 0; k < 3; ++k) right.p[k] = c[k];
    load_channels(row, x - 2, c);
    left2z = c[2];
    load_channels(row, x + 2, c);
    right2z = c[2];
    left.seen = seen_mask(r.seen[2], x - 1);
    right.seen = seen_mask(r.seen[2], x + 1);
    const VI left2_seen = seen_mask(r.seen[2], x - 2), right2_seen = seen_mask(r.seen[2], x + 2);
    // Along y: the same texels of rows y - 2 .. y + 2 (zeros off the image, never picked).
    Side up, down;
    VF up2z = {}, down2z = {};
    for (int k = 0; k < 3; ++k) up.p[k] = down.p[k] = VF{};
    if (r.position[1]) {
      load_channels(r.position[1], x, c);
      for (int k = 0; k < 3; ++k) up.p[k] = c[k];
    }
    if (r.position[3]) {
      load_channels(r.position[3], x, c);
      for (int k = 0; k < 3; ++k) down.p[k] = c[k];
    }
    if (r.position[0]) {
      load_channels(r.position[0], x, c);
      up2z = c[2];
    }
    if (r.position[4]) {
      load_channels(r.position[4], x, c);
      down2z = c[2];
    }
    up.seen = seen_mask(r.seen[1], x);
    down.seen = seen_mask(r.seen[3], x);
    const VI up2_seen = seen_mask(r.seen[0], x), down2_seen = seen_mask(r.seen[4], x);

    VF s[4];
    load_channels(r.normal, x, s);
    const VI finite = (s[0] - s[0] == splat(0.0f)) & (s[1] - s[1] == splat(0.0f)) & (s[2] - s[2] == splat(0.0f));
    const VI nonzero = (s[0] != splat(0.0f)) | (s[1] != splat(0.0f)) | (s[2] != splat(0.0f));
    VF ex[3], ey[3];
    const VI has_x = axis_difference(p, left, left2z, left2_seen, right, right2z, right2_seen, ex);
    const VI has_y = axis_difference(p, up, up2z, up2_seen, down, down2z, down2_seen, ey);
    const VF cr[3] = {ex[1] * ey[2] - ex[2] * ey[1], ex[2] * ey[0] - ex[0] * ey[2], ex[0] * ey[1] - ex[1] * ey[0]};
    const VF len2 = cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2];
    const VI good = seen_mask(r.seen[2], x) & finite & nonzero & has_x & has_y & (len2 > splat(0.0f)) &
                    (len2 - len2 == splat(0.0f));
    VF inv = splat(1.0f) / reinterpret_cast<VF>(_mm256_sqrt_ps(reinterpret_cast<__m256>(len2)));
    inv = pick(s[0] * cr[0] + s[1] * cr[1] + s[2] * cr[2] < splat(0.0f), -inv, inv);
    VF o[3];
    for (int k = 0; k < 3; ++k) o[k] = pick(good, cr[k] * inv, s[k]);
    float* out = r.out + static_cast<size_t>(x) * 3;
    for (int l = 0; l < 8; ++l) {
      out[3 * l] = o[0][l];
      out[3 * l + 1] = o[1][l];
      out[3 * l + 2] = o[2][l];
    }
  }
}

}  // namespace glint::cpu
