// The specular buffer's encoding and what every stage reads from a pixel of
// it (docs/conventions.md): one definition, inline, for both backends'
// C++, the GLSL twins in shaders/common.glsl and look_common.glsl (same
// operation order) and the add-on (addon/glint/logic/materials.py). The
// numbers are glint/schema.h's.
#pragma once
#include <cmath>

#include "glint/brdf.h"
#include "glint/image.h"
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
// The cone blur's level of detail at pixel (x, y) of a w x h image: log2 of
// the footprint 2 * |hit uv - pixel centre| (pixels) * cone_tan(alpha), 0
// where the footprint is within one pixel or the pixel reports no hit (vis
// uv[2] <= 0) or is a mirror. `uv` and `spec` are that pixel's texels. Both
// backends' cone blur and the add-on's compositor blur read this one rule.
inline float cone_lod_at(int x, int y, int w, int h, const float* uv, const float* spec) {
  if (!(uv[2] > 0.0f) || !(uv[0] - uv[0] == 0.0f) || !(uv[1] - uv[1] == 0.0f)) return 0.0f;
  const float alpha = ggx_alpha_of(spec);
  if (!(alpha > 0.0f)) return 0.0f;
  const float dx = uv[0] * static_cast<float>(w) - (static_cast<float>(x) + 0.5f);
  const float dy = uv[1] * static_cast<float>(h) - (static_cast<float>(y) + 0.5f);
  const float footprint = 2.0f * std::sqrt(dx * dx + dy * dy) * cone_tan(alpha);
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
Image cone_lod(const Image& uv, const Image& specular);
}  // namespace glint
