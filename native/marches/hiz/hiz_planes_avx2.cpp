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

// Texels x .. x + 7 of one row as plane_normal() sees them: their positions
// and whether each is seen (zeros and unseen where the row is off the image:
// the masks never pick those values).
struct Side {
  VF p[3];
  VI seen;
};
__attribute__((always_inline)) inline Side side_at(const float* row, const unsigned char* seen, int x) {
  Side s{};
  if (row) {
    VF c[4];
    load_channels(row, x, c);
    for (int k = 0; k < 3; ++k) s.p[k] = c[k];
  }
  s.seen = seen_mask(seen, x);
  return s;
}

// miss(): how far the depth this side predicts misses p's; a1 the adjacent
// texels, a2 the ones beyond (their z only).
__attribute__((always_inline)) inline VF miss(VF pz, const Side& a1, const Side& a2) {
  return pick(a2.seen, vabs((splat(2.0f) * a1.p[2] - a2.p[2]) - pz), vabs(a1.p[2] - pz));
}

// axis_difference() on the lanes: e, and whether either neighbour is seen.
__attribute__((always_inline)) inline VI axis_difference(const VF p[3], const Side& lo, const Side& lo2,
                                                         const Side& hi, const Side& hi2, VF e[3]) {
  const VI lower_better = lo.seen & hi.seen & (miss(p[2], lo, lo2) < miss(p[2], hi, hi2));
  const VI use_hi = hi.seen & ~lower_better;
  for (int k = 0; k < 3; ++k) e[k] = pick(use_hi, hi.p[k] - p[k], p[k] - lo.p[k]);
  return hi.seen | lo.seen;
}

}  // namespace

void hiz_plane_normals_row_avx2(const PlaneRow& r, int x_begin, int x_end) {
  const float* row = r.position[2];
  const unsigned char* seen = r.seen[2];
  for (int x = x_begin; x + 8 <= x_end; x += 8) {
    const Side self = side_at(row, seen, x);
    const VF* p = self.p;
    // Along x the row's own texels at x - 2 .. x + 2; along y the same texels
    // of rows y - 2 .. y + 2.
    VF ex[3], ey[3];
    const VI has_x = axis_difference(p, side_at(row, seen, x - 1), side_at(row, seen, x - 2),
                                     side_at(row, seen, x + 1), side_at(row, seen, x + 2), ex);
    const VI has_y = axis_difference(p, side_at(r.position[1], r.seen[1], x), side_at(r.position[0], r.seen[0], x),
                                     side_at(r.position[3], r.seen[3], x), side_at(r.position[4], r.seen[4], x), ey);
    VF s[4];
    load_channels(r.normal, x, s);
    const VI finite_normal = finite(s[0]) & finite(s[1]) & finite(s[2]);
    const VI nonzero = (s[0] != splat(0.0f)) | (s[1] != splat(0.0f)) | (s[2] != splat(0.0f));
    const VF cr[3] = {ex[1] * ey[2] - ex[2] * ey[1], ex[2] * ey[0] - ex[0] * ey[2], ex[0] * ey[1] - ex[1] * ey[0]};
    const VF len2 = cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2];
    const VI good = self.seen & finite_normal & nonzero & has_x & has_y & (len2 > splat(0.0f)) &
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

void hiz_seen_row_avx2(const float* position, int n, unsigned char* out) {
  for (int x = 0; x + 8 <= n; x += 8) {
    VF c[4];
    load_channels(position, x, c);
    // Lanes 0/-1 to bytes 0/1, in lane order.
    const __m256i one = reinterpret_cast<__m256i>(texel_seen(c) & 1);
    const __m128i words = _mm_packs_epi32(_mm256_castsi256_si128(one), _mm256_extracti128_si256(one, 1));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + x), _mm_packus_epi16(words, words));
  }
}

}  // namespace glint::cpu
