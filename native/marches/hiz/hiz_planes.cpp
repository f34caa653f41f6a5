// The hiz march's plane normals: each texel's geometric normal rebuilt from
// the position buffer (hiz.h says the rule, docs/hiz.md why). The GL
// backend runs the same steps in hiz_planes.glsl (from hiz_base.frag), in the same order.
#include <cmath>

#include "glint/stages.h"
#include "hiz.h"
#include "hiz_base.h"

namespace glint::cpu {
namespace {

// The seen texel `k` steps from (x, y) along (ax, ay), or null.
inline const float* neighbour(const Image& position, const SeenRows& seen, int x, int y, int ax, int ay, int k) {
  const int nx = x + k * ax, ny = y + k * ay;
  if (nx < 0 || ny < 0 || nx >= position.width || ny >= position.height) return nullptr;
  return seen.at(nx, ny) ? position.px(nx, ny) : nullptr;
}

// How far the depth one side predicts for the texel misses its own: the line
// through that side's two texels where both are seen, else its adjacent one.
// The line is what tells a grazing floor's texel from the wall it meets: the
// wall's base can be closer in depth than the floor's next texel.
float miss(const float* p, const float* a1, const float* a2) {
  return a2 ? std::fabs((2.0f * a1[2] - a2[2]) - p[2]) : std::fabs(a1[2] - p[2]);
}

// The difference along one axis: toward the seen neighbour whose side
// predicts the texel's depth better (the high one on a tie), always from low
// to high so both axes' differences keep one handedness. False when neither
// neighbour is seen.
__attribute__((always_inline)) inline bool axis_difference(const Image& position, const SeenRows& seen,
                                                           const float* p, int x, int y, int ax, int ay, float e[3]) {
  const float* lo = neighbour(position, seen, x, y, ax, ay, -1);
  const float* hi = neighbour(position, seen, x, y, ax, ay, 1);
  if (hi && lo &&
      miss(p, lo, neighbour(position, seen, x, y, ax, ay, -2)) <
          miss(p, hi, neighbour(position, seen, x, y, ax, ay, 2)))
    hi = nullptr;
  if (hi) {
    for (int k = 0; k < 3; ++k) e[k] = hi[k] - p[k];
  } else if (lo) {
    for (int k = 0; k < 3; ++k) e[k] = p[k] - lo[k];
  } else {
    return false;
  }
  return true;
}

void plane_normal(const Image& position, const Image& normal, const SeenRows& seen, int x, int y, float out[4]) {
  const float* s = normal.px(x, y);
  out[0] = s[0];
  out[1] = s[1];
  out[2] = s[2];
  const float* p = position.px(x, y);
  if (!seen.at(x, y) || !(s[0] - s[0] == 0.0f && s[1] - s[1] == 0.0f && s[2] - s[2] == 0.0f) ||
      (s[0] == 0.0f && s[1] == 0.0f && s[2] == 0.0f))
    return;
  float ex[3], ey[3];
  if (!axis_difference(position, seen, p, x, y, 1, 0, ex) || !axis_difference(position, seen, p, x, y, 0, 1, ey))
    return;
  const float c[3] = {ex[1] * ey[2] - ex[2] * ey[1], ex[2] * ey[0] - ex[0] * ey[2], ex[0] * ey[1] - ex[1] * ey[0]};
  const float len2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
  // Collinear neighbours, or differences too small or large for a float square.
  if (!(len2 > 0.0f) || len2 - len2 != 0.0f) return;
  float inv = 1.0f / std::sqrt(len2);
  if (s[0] * c[0] + s[1] * c[1] + s[2] * c[2] < 0.0f) inv = -inv;
  out[0] = c[0] * inv;
  out[1] = c[1] * inv;
  out[2] = c[2] * inv;
}

}  // namespace

void fill_seen_rows(const Image& position, int y0, int y1, SeenRows& out, WalkIsa isa) {
  out.y0 = y0;
  out.width = position.width;
  out.bytes.resize(static_cast<size_t>(y1 - y0) * position.width);
  for (int y = y0; y < y1; ++y) {
    const float* p = position.px(0, y);
    unsigned char* o = out.bytes.data() + static_cast<size_t>(y - y0) * position.width;
    int x = 0;
#if defined(GLINT_WALK_AVX2)
    if (isa == WalkIsa::Avx2) {
      x = position.width / 8 * 8;
      hiz_seen_row_avx2(p, x, o);
    }
#else
    (void)isa;
#endif
    // texel_seen() with & for &&: no branch per test (the baseline compiler
    // did not vectorise it all the same: hence the AVX2 rows).
    for (; x < position.width; ++x) {
      const float* q = p + static_cast<size_t>(x) * 4;
      o[x] = (q[3] > 0.0f) & (q[0] - q[0] == 0.0f) & (q[1] - q[1] == 0.0f) & (q[2] - q[2] == 0.0f) &
             (q[3] - q[3] == 0.0f);
    }
  }
}

void hiz_plane_normals_row(const Image& position, const Image& normal, const SeenRows& seen, int y,
                           HizPlanes& out, WalkIsa isa) {
  int x_begin = 0, x_end = 0;  // the texels left to the AVX2 rows, if any
#if defined(GLINT_WALK_AVX2)
  if (isa == WalkIsa::Avx2 && position.width >= 12) {
    PlaneRow r;
    for (int k = 0; k < 5; ++k) {
      const int yy = y - 2 + k;
      if (yy < 0 || yy >= position.height) continue;
      r.position[k] = position.px(0, yy);
      r.seen[k] = seen.bytes.data() + static_cast<size_t>(yy - seen.y0) * seen.width;
    }
    r.normal = normal.px(0, y);
    r.out = out.px(0, y);
    x_begin = 2;
    x_end = x_begin + (position.width - 4) / 8 * 8;
    hiz_plane_normals_row_avx2(r, x_begin, x_end);
  }
#else
  (void)isa;
#endif
  for (int x = 0; x < x_begin; ++x) plane_normal(position, normal, seen, x, y, out.px(x, y));
  for (int x = x_end; x < position.width; ++x) plane_normal(position, normal, seen, x, y, out.px(x, y));
}

}  // namespace glint::cpu
