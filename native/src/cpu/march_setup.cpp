// What the screen-space marches (seed, linear) set up once per frame: the
// view-distance buffer and the per-frame constants (march.h).
#include <limits>
#include <vector>

#include "march.h"
#include "parallel.h"
#include "ray.h"

namespace glint::cpu {

void fill_view_distance(const Image& position, int y, float* out) {
  for (int x = 0; x < position.width; ++x) {
    const float* p = position.px(x, y);
    out[x] = texel_seen(p) ? view_distance({p[0], p[1], p[2]}) : std::numeric_limits<float>::quiet_NaN();
  }
}

MarchSetup make_setup(const Image& position, const Image& normal, const Mat4& projection,
                      const TraceOptions& opt, const float* view_distance) {
  MarchSetup s;
  s.position = &position;
  s.normal = &normal;
  s.view_distance = view_distance;
  for (int i = 0; i < 16; ++i) {
    s.projd[i] = projection.m[i];
    s.proj[i] = static_cast<float>(projection.m[i]);
  }
  s.kind = classify_projection(projection);
  s.opt = opt;
  const CameraEye ce = camera_eye(projection);
  s.eye_kind = ce.kind;
  for (int k = 0; k < 3; ++k) s.eye[k] = ce.eye[k];
  return s;
}

std::vector<float> view_distances(const Image& position, int threads) {
  std::vector<float> vd(position.pixel_count());
  parallel_rows(0, position.height, threads, [&](int y) {
    fill_view_distance(position, y, vd.data() + static_cast<size_t>(y) * position.width);
  });
  return vd;
}

}  // namespace glint::cpu
