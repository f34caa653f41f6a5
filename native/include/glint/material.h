// The specular buffer's encoding and what every stage reads from a pixel of
// it (docs/conventions.md): one definition, inline, for both backends'
// C++, the GLSL twins in shaders/common.glsl and look_common.glsl (same
// operation order) and the add-on (addon/glint/logic/materials.py). The
// numbers are glint/schema.h's.
#pragma once
#include <cmath>

#include "glint/brdf.h"
#include "glint/image.h"
#include "glint/projection.h"
#include "glint/schema.h"

namespace glint {

// Specular amount and roughness of one specular-buffer pixel, as the seed's
// reflection pass defines them. Shared so every backend and test agrees.
inline float specular_amount(const float* spec) { return (spec[0] + spec[1] + spec[2]) / 3.0f; }
// Roughness = 1 - clamp(shininess, 0, 1): the seed's 1 - min(a, 1) would let
// a negative value extrapolate past the blurred colour. A non-finite
// shininess counts as 1 (smooth), in the reflection stage and in deciding
// whether the blur is needed alike.
inline float roughness_of(const float* spec) {
  const float s = spec[3] - spec[3] == 0.0f ? spec[3] : 1.0f;
  return 1.0f - (s < 0.0f ? 0.0f : (s > 1.0f ? 1.0f : s));
}
// GGX width alpha (Blender's Roughness squared) of a specular-buffer pixel:
// the inverse of the add-on's mapping (docs/addon.md) shininess alpha =
// hardness / 511 with hardness = 2 / alpha^2 - 2. Alpha 1 (hardness 511, the
// book's largest) is a mirror, alpha 0, so that pixels roughness_of() calls
// smooth are smooth here too. Above 1 is the gloss range (docs/conventions.md):
// hardness past Blender Internal's 511, which the add-on writes for Principled
// roughness below 0.25; roughness_of() reads it as smooth (the book's mix has
// no gloss), the cone as the GGX lobe it is. docs/look-core.md.
inline float ggx_alpha_of(const float* spec) {
  const float r = roughness_of(spec);
  float hardness;
  if (r > 0.0f) {
    hardness = (1.0f - r) * (kHardnessPerShininess * kMaxShininess);
  } else {
    if (!(spec[3] > 1.0f) || !(spec[3] - spec[3] == 0.0f)) return 0.0f;
    hardness = spec[3] * (kHardnessPerShininess * kMaxShininess);
  }
  return std::sqrt(2.0f / (hardness + 2.0f));
}
// Whether the cone blurs a pixel's reflection: its lobe has a width.
inline bool is_glossy(const float* spec) { return ggx_alpha_of(spec) > 0.0f; }
// The split-sum weight F0 * A + B of specular-buffer pixel `spec` seen at
// n_dot_v (in [0, 1]), per channel, from the table at hand
// (env_brdf_table().data()): what Backend::specular_weight() writes for the
// camera's view, and what the composite asks for other views.
inline void split_sum_weight(const float* table, const float* spec, float n_dot_v, float w[3]) {
  float a, b;
  env_brdf_lookup(table, n_dot_v, ggx_alpha_of(spec), &a, &b);
  for (int k = 0; k < 3; ++k) w[k] = spec[k] * a + b;
}
// tan of the half-angle of a GGX reflection cone: the half-vector cone that
// holds half of D's projected mass has tan = alpha, the reflected direction
// turns twice as far: tan(2 atan(alpha)) = 2 alpha / (1 - alpha^2), capped
// at kMaxConeTan (glint/schema.h) where the cone opens to a half-space.
inline float cone_tan(float alpha) {
  const float d = 1.0f - alpha * alpha;
  const float t = 2.0f * alpha;
  return d * kMaxConeTan > t ? t / d : kMaxConeTan;
}
// What bounds the cone's footprint by a flat mirror's (docs/look-core.md, "No
// wider than a flat mirror"): the G-buffer's view positions and the camera.
// A flat mirror at view point p shows a hit t away where p's own camera ray,
// carried on by t, would be; a cone 2 t tan across there spans 2 t tan times
// the pixels a view unit covers at that point. The screen distance to the hit
// can make the footprint larger than that (a convex mirror shows its hits
// smaller than a flat one; so does a hit far across the screen but far from
// the camera), never rightly so. mirror_scale() fills it from a projection.
struct MirrorScale {
  const Image* position = nullptr;  // null: the footprint is not bounded
  CameraEye eye;
  float pixels_per_unit = 0.0f;  // (height / 2) |P(1, 1)|: pixels per view unit where clip w = 1
  float w_row[4] = {0.0f, 0.0f, 0.0f, 0.0f};  // P's last row: clip w of a view point
};
MirrorScale mirror_scale(const Image& position, const Mat4& projection);

// The flat mirror's footprint at pixel (x, y) whose hit is at `uv`, 0 where it
// is not known (the hit off the image, either texel unseen, or the carried
// point not in front).
inline float mirror_footprint(int x, int y, const float* uv, float tan_c, const MirrorScale& m) {
  const Image& pos = *m.position;
  const float* p = pos.px(x, y);
  int hx = 0, hy = 0;
  if (!pos.texel_at(uv[0] * static_cast<float>(pos.width), uv[1] * static_cast<float>(pos.height), hx, hy))
    return 0.0f;
  const float* q = pos.px(hx, hy);
  if (!(p[3] > 0.0f) || !(q[3] > 0.0f)) return 0.0f;
  const float ex = q[0] - p[0], ey = q[1] - p[1], ez = q[2] - p[2];
  const float t = std::sqrt(ex * ex + ey * ey + ez * ez);
  float d[3];
  incident_toward(m.eye, p, d);
  const float dn = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (!(dn > 0.0f)) return 0.0f;
  const float s = t / dn;
  const float vx = p[0] + s * d[0], vy = p[1] + s * d[1], vz = p[2] + s * d[2];
  const float cw = m.w_row[0] * vx + m.w_row[1] * vy + m.w_row[2] * vz + m.w_row[3];
  const float f = 2.0f * t * tan_c * (m.pixels_per_unit / cw);
  return cw > 0.0f && f - f == 0.0f ? f : 0.0f;
}

// The cone blur's level of detail at pixel (x, y) of a w x h image: log2 of
// the footprint 2 * |hit uv - pixel centre| (pixels) * cone_tan(alpha), no
// wider than a flat mirror's where `mirror` is given and knows it, 0 where
// the footprint is within one pixel or the pixel reports no hit (vis uv[2]
// <= 0) or is a mirror. `uv` and `spec` are that pixel's texels. Both
// backends' cone blur and the add-on's compositor blur read this one rule;
// the trace's outline search asks it without `mirror` (docs/look-core.md).
inline float cone_lod_at(int x, int y, int w, int h, const float* uv, const float* spec,
                         const MirrorScale* mirror = nullptr) {
  if (!(uv[2] > 0.0f) || !(uv[0] - uv[0] == 0.0f) || !(uv[1] - uv[1] == 0.0f)) return 0.0f;
  const float alpha = ggx_alpha_of(spec);
  if (!(alpha > 0.0f)) return 0.0f;
  const float dx = uv[0] * static_cast<float>(w) - (static_cast<float>(x) + 0.5f);
  const float dy = uv[1] * static_cast<float>(h) - (static_cast<float>(y) + 0.5f);
  const float tan_c = cone_tan(alpha);
  float footprint = 2.0f * std::sqrt(dx * dx + dy * dy) * tan_c;
  // The bound only narrows: a footprint already within a pixel needs none.
  if (footprint > 1.0f && mirror && mirror->position) {
    const float flat = mirror_footprint(x, y, uv, tan_c, *mirror);
    if (flat > 0.0f && flat < footprint) footprint = flat;
  }
  return footprint > 1.0f ? std::log2(footprint) : 0.0f;
}
// True when a position texel counts as "seen": w > 0 and every channel finite.
inline bool texel_seen(const float* p) {
  return p[3] > 0.0f && p[0] - p[0] == 0.0f && p[1] - p[1] == 0.0f && p[2] - p[2] == 0.0f &&
         p[3] - p[3] == 0.0f;
}

// The thickness the back-face layer gives texel (x, y) of `position`, or -1
// where it gives none (no layer, no back surface behind it).
inline float known_thickness(const Image& position, const Image* back, int x, int y) {
  if (!back) return -1.0f;
  const float* b = back->px(x, y);
  const float d = -position.px(x, y)[2];
  return texel_seen(b) && -b[2] > d ? -b[2] - d : -1.0f;
}

// The thickness of texel (x, y): how far behind its surface still counts, the
// back layer's where it has one, else `thickness` (TraceOptions::thickness).
inline float texel_thickness(const Image& position, const Image* back, float thickness, int x, int y) {
  const float t = known_thickness(position, back, x, y);
  return t > 0.0f ? t : thickness;
}

// A pixel is reflective when its specular amount is positive (and finite).
// Inline: a frame asks it of every pixel several times over.
inline bool is_reflective(const float* spec) {
  const float amount = specular_amount(spec);
  return amount > 0.0f && amount - amount == 0.0f;
}

// Material specular, the book's mapping: Blender Internal hardness 1..511,
// shininess = hardness / 4 (511 -> 127.75), alpha = shininess / 127.75, 0 for
// a negative or non-finite shininess. Not capped at 1: a shininess above
// 127.75 is the gloss range (ggx_alpha_of()).
inline float shininess_from_hardness(float hardness) { return hardness / kHardnessPerShininess; }
float shininess_to_alpha(float shininess);

// Each pixel's cone_lod_at() as a one-channel image in r (g, b, a zero):
// what a compositor outside the core needs to blur a reflection it samples
// itself the way cone_blur would. Checks its inputs as cone_blur does.
Image cone_lod(const Image& uv, const Image& specular, const MirrorScale* mirror = nullptr);
}  // namespace glint
