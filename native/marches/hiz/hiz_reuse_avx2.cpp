// The G-buffer half of the second pass's reuse test (hiz_reuse.cpp's
// reuse_surface()) for x86-64 CPUs with AVX2: eight pixels of a row at once,
// one per lane. Like the other *_avx2.cpp files, this one alone is built with
// -mavx2 and not -mfma and includes no inline functions but
// hiz_lanes_avx2.h's. Each lane does the scalar test's float operations in its
// order, so the bytes are the scalar ones bit for bit (test_hiz_walk compares
// the two paths' bytes row by row).
//
// Why: three pixels in four of a balanced trace are answered by this test,
// each against two or four neighbours. As a loop of branches per neighbour it
// was a fifth of a single-thread 1080p trace; here a row is read in order
// and every lane computes every neighbour, parity picking which count.
#include <immintrin.h>

#include "hiz_base.h"
#include "hiz_lanes_avx2.h"

namespace glint::cpu {
namespace {

// Texels x .. x + 7 of one of the rows: position, shading normal, and
// whether each reflects (every lane where there is no specular buffer).
struct Texels {
  VF p[4], n[4];
  VI reflective;
};
__attribute__((always_inline)) inline Texels texels_at(const ReuseRow& r, int row, int x) {
  Texels t;
  load_channels(r.position[row], x, t.p);
  load_channels(r.normal[row], x, t.n);
  if (r.specular[row]) {
    VF s[4];
    load_channels(r.specular[row], x, s);
    const VF amount = (s[0] + s[1] + s[2]) / splat(3.0f);  // specular_amount()
    t.reflective = (amount > splat(0.0f)) & finite(amount);
  } else {
    t.reflective = ~VI{};
  }
  return t;
}

// same_surface() of neighbour q against the pixel c, with normals_agree().
__attribute__((always_inline)) inline VI same(const ReuseRow& r, const Texels& c, const Texels& q) {
  const VI near = vabs(q.p[2] - c.p[2]) <= splat(r.depth_share) * vabs(c.p[2]);
  const VF nn = c.n[0] * c.n[0] + c.n[1] * c.n[1] + c.n[2] * c.n[2];
  const VF d = c.n[0] * q.n[0] + c.n[1] * q.n[1] + c.n[2] * q.n[2];
  const VF mm = q.n[0] * q.n[0] + q.n[1] * q.n[1] + q.n[2] * q.n[2];
  return q.reflective & texel_seen(q.p) & near & (d > splat(0.0f)) & (d * d >= splat(r.cos2) * nn * mm);
}

}  // namespace

void hiz_reuse_row_avx2(const ReuseRow& r, int x_begin, int x_end) {
  const bool odd_row = (r.y & 1) != 0;
  for (int x = x_begin; x + 8 <= x_end; x += 8) {
    const Texels c = texels_at(r, 1, x);
    // The pixel's own ray exists (read_origin() would take it).
    const VI valid = c.reflective & texel_seen(c.p) & finite(c.n[0]) & finite(c.n[1]) & finite(c.n[2]);
    const VI lane = VI{0, 1, 2, 3, 4, 5, 6, 7} + x;
    const VI odd_x = (lane & 1) != 0;
    VI ok;
    if (!odd_row) {
      // Odd columns, from the two beside them; even columns were traced.
      ok = odd_x & same(r, c, texels_at(r, 1, x - 1)) & same(r, c, texels_at(r, 1, x + 1));
    } else {
      // Even columns from the pixels above and below, odd ones from the four
      // at their corners.
      const VI column = same(r, c, texels_at(r, 0, x)) & same(r, c, texels_at(r, 2, x));
      const VI corners = same(r, c, texels_at(r, 0, x - 1)) & same(r, c, texels_at(r, 0, x + 1)) &
                         same(r, c, texels_at(r, 2, x - 1)) & same(r, c, texels_at(r, 2, x + 1));
      ok = (odd_x & corners) | (~odd_x & column);
    }
    const int bits = _mm256_movemask_ps(reinterpret_cast<__m256>(valid & ok));
    for (int l = 0; l < 8; ++l) r.out[x + l] = static_cast<unsigned char>((bits >> l) & 1);
  }
}

}  // namespace glint::cpu
