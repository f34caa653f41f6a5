// The pixel's own ray and its near-plane clip; see ray.h.
#include "ray.h"

namespace glint::cpu {

bool read_origin(const MarchSetup& s, int x, int y, V3& from, V3& unit_from, V3& normal) {
  const float* p = s.position->px(x, y);
  if (!texel_seen(p)) return false;
  const float* n = s.normal->px(x, y);
  normal = {n[0], n[1], n[2]};
  if (!finite(normal) || dot(normal, normal) == 0.0f) return false;
  from = {p[0], p[1], p[2]};
  if (!incident_direction(s, from, unit_from)) return false;
  normal = normalize(normal);
  return finite(normal);
}

bool incident_direction(const MarchSetup& s, V3 from, V3& unit_from) {
  // The seed's normalize(position) is the view ray of a camera at the origin.
  // An orthographic camera's view rays are parallel, so reflecting
  // normalize(position) there would mirror the wrong ray.
  if (s.eye_kind == MarchSetup::Eye::Origin) {
    if (dot(from, from) == 0.0f) return false;
    unit_from = normalize(from);
  } else if (s.eye_kind == MarchSetup::Eye::Point) {
    const V3 d = from - V3{s.eye[0], s.eye[1], s.eye[2]};
    if (dot(d, d) == 0.0f) return false;
    unit_from = normalize(d);
  } else {
    unit_from = {s.eye[0], s.eye[1], s.eye[2]};
  }
  return finite(unit_from);
}

float clipped_length(const MarchSetup& s, V3 from, V3 dir, float max_distance) {
  const double* P = s.projd;
  auto near_fn = [&](double x, double y, double z) {
    return clip_row(P, 2, x, y, z) + clip_row(P, 3, x, y, z);
  };
  const double n0 = near_fn(from.x, from.y, from.z);
  if (!(n0 >= 0.0) || !(clip_row(P, 3, from.x, from.y, from.z) > 0.0)) return -1.0f;
  double len = max_distance;
  const double n1 = near_fn(from.x + dir.x * len, from.y + dir.y * len, from.z + dir.z * len);
  if (n1 < 0.0) len = len * (n0 / (n0 - n1));
  const float full = static_cast<float>(len);
  float lf = full;
  float shrink = 1.0f / 4194304.0f;  // 2^-22: two float steps of the length
  for (int i = 0; i < 64; ++i) {
    const V3 e = from + dir * lf;
    if (near_fn(e.x, e.y, e.z) >= 0.0 && clip_row(P, 3, e.x, e.y, e.z) > 0.0) return lf;
    lf = full * (1.0f - shrink);
    shrink = shrink * 2.0f > 1.0f ? 1.0f : shrink * 2.0f;
  }
  return 0.0f;
}

}  // namespace glint::cpu
