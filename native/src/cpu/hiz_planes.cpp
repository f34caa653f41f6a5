// The hiz march's plane normals: each texel's geometric normal rebuilt from
// the position buffer (hiz.h says the rule, docs/marches.md why). The GL
// backend runs the same steps in shaders/hiz_planes.frag, in the same order.
#include <cmath>

#include "glint/stages.h"
#include "hiz.h"
#include "parallel.h"

namespace glint::cpu {
namespace {

// The difference along one axis: toward the seen neighbour whose depth is
// closer to the texel's (the high one on a tie), always from low to high so
// both axes' differences keep one handedness. False when neither is seen.
bool axis_difference(const Image& position, const float* p, int x, int y, int ax, int ay, float e[3]) {
  const int w = position.width, h = position.height;
  const float* lo = nullptr;
  const float* hi = nullptr;
  if (x - ax >= 0 && y - ay >= 0 && texel_seen(position.px(x - ax, y - ay))) lo = position.px(x - ax, y - ay);
  if (x + ax < w && y + ay < h && texel_seen(position.px(x + ax, y + ay))) hi = position.px(x + ax, y + ay);
  if (hi && lo && std::fabs(lo[2] - p[2]) < std::fabs(hi[2] - p[2])) hi = nullptr;
  if (hi) {
    for (int k = 0; k < 3; ++k) e[k] = hi[k] - p[k];
  } else if (lo) {
    for (int k = 0; k < 3; ++k) e[k] = p[k] - lo[k];
  } else {
    return false;
  }
  return true;
}

void plane_normal(const Image& position, const Image& normal, int x, int y, float out[4]) {
  const float* s = normal.px(x, y);
  out[0] = s[0];
  out[1] = s[1];
  out[2] = s[2];
  out[3] = 0.0f;
  const float* p = position.px(x, y);
  if (!texel_seen(p) || !(s[0] - s[0] == 0.0f && s[1] - s[1] == 0.0f && s[2] - s[2] == 0.0f) ||
      (s[0] == 0.0f && s[1] == 0.0f && s[2] == 0.0f))
    return;
  float ex[3], ey[3];
  if (!axis_difference(position, p, x, y, 1, 0, ex) || !axis_difference(position, p, x, y, 0, 1, ey)) return;
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

Image hiz_plane_normals(const Image& position, const Image& normal, int threads) {
  Image out(position.width, position.height);
  parallel_rows(0, position.height, threads, [&](int y) {
    for (int x = 0; x < position.width; ++x) plane_normal(position, normal, x, y, out.px(x, y));
  });
  return out;
}

}  // namespace glint::cpu
