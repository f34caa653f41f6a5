// The pipeline's stages, each a plain function of images, and the Backend
// interface that every implementation (CPU reference, OpenGL) provides, so a
// stage can be run and compared on either.
//
//   G-buffer (position, normal, specular)
//     -> trace            reflected uv + visibility  (u, v, vis, vis)
//     -> reflection_color colour at the reflected uv, premultiplied by visibility
//     -> specular_weight  F0 * A + B from the split-sum table (weighting "physical")
//     -> cone_blur        per-pixel footprint from a mip chain (blur "cone"), or
//        box_blur         (2 * size + 1)^2 box of the reflection colour (blur "box")
//     -> reflection       blurred colour * weight (or the seed's amount)
//     -> combine          the reflection over the base image, optionally replacing
//                         the engine's own specular
#pragma once
#include <cmath>
#include <memory>
#include <string>

#include "glint/image.h"
#include "glint/options.h"
#include "glint/projection.h"
#include "glint/raster.h"

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
// hardness / 511 with hardness = clamp(2 / alpha^2 - 2, 1, 511). The clamp at
// 511 (every Roughness <= 0.25) reads as a mirror, alpha 0, so that pixels
// roughness_of() calls smooth are smooth here too. docs/look-core.md.
inline float ggx_alpha_of(const float* spec) {
  const float r = roughness_of(spec);
  if (!(r > 0.0f)) return 0.0f;
  const float hardness = (1.0f - r) * (kHardnessPerShininess * kMaxShininess);
  return std::sqrt(2.0f / (hardness + 2.0f));
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

// A pixel is reflective when its specular amount is positive (and finite).
// Inline: a frame asks it of every pixel several times over.
inline bool is_reflective(const float* spec) {
  const float amount = specular_amount(spec);
  return amount > 0.0f && amount - amount == 0.0f;
}

// Material specular, the book's mapping: Blender Internal hardness 1..511,
// shininess = hardness / 4 (511 -> 127.75), alpha = clamp(shininess / 127.75, 0, 1).
inline float shininess_from_hardness(float hardness) { return hardness / kHardnessPerShininess; }
float shininess_to_alpha(float shininess);

// What the trace stage needs to know about which pixels matter. With a
// specular buffer, pixels whose specular amount is zero are not traced and
// report (0, 0, 0, 0); without one every seen pixel is traced.
struct TriangleMesh;  // glint/mesh.h

struct TraceInputs {
  const Image& position;
  const Image& normal;
  const Image* specular = nullptr;
  Mat4 projection;
  // Optional: the nearest surface behind each pixel's own, same layout as
  // `position` (w = 0 where there is none). Marches that read it use
  // back - front as that texel's true thickness instead of the option.
  const Image* back_position = nullptr;
  // The triangles the G-buffer was made from, for marches that need them.
  const TriangleMesh* mesh = nullptr;
};

class Backend {
 public:
  virtual ~Backend() = default;
  virtual std::string name() const = 0;

  // Reflected uv buffer (u, v, visibility, visibility).
  virtual Image trace(const TraceInputs& in, const TraceOptions& opt) = 0;
  // color sampled (bilinear, clamp to edge) at uv.xy, times clamp(uv.b, 0, 1);
  // alpha = clamp(uv.b, 0, 1). Pixels with zero visibility stay (0, 0, 0, 0).
  virtual Image reflection_color(const Image& uv, const Image& color) = 0;
  // Box blur of all four channels (the colour is premultiplied, so alpha must
  // follow it). Only pixels inside `region` (x0, y0, x1, y1, half-open) are
  // blurred; the rest are copied from src. region == nullptr: the whole image.
  virtual Image box_blur(const Image& src, const BlurOptions& opt, const int* region) = 0;
  // rgb weight of each pixel's reflection (docs/look-core.md): F0 * A + B per
  // channel, F0 = specular rgb, (A, B) the split-sum table (glint/brdf.h) at
  // N.V (the camera's real view ray, camera_eye()) and ggx_alpha_of(specular);
  // alpha = mean of the rgb. (0, 0, 0, 0) where a pixel is not seen, not
  // reflective or has no usable normal.
  virtual Image specular_weight(const Image& position, const Image& normal, const Image& specular,
                                const Mat4& projection) = 0;
  // The reflection colour blurred by each pixel's GGX cone: a footprint of
  // 2 * ray length in pixels (|uv - pixel centre|) * cone_tan(alpha), read
  // trilinearly from a 2x2 box mip chain of `color` (all four channels).
  // Pixels with alpha 0, zero visibility or no reflection keep their colour.
  virtual Image cone_blur(const Image& color, const Image& uv, const Image& specular) = 0;
  // mix(color, *blurred, roughness) (just `color` when blurred is null: a cone
  // blur already holds the roughness) times the weight: weight->rgb on the
  // colour and weight->a on the alpha, or the seed's specular amount on all
  // four when weight is null. 0 where the pixel does not reflect.
  virtual Image reflection(const Image& color, const Image* blurred, const Image& specular,
                           const Image* weight) = 0;
  Image reflection(const Image& color, const Image& blurred, const Image& specular) {
    return reflection(color, &blurred, specular, nullptr);
  }
  // The reflection over the base (Combine). With specular_base (the engine's
  // own specular contribution, "over" only), the part of it that the
  // reflection stands in for is taken out first:
  //   max(base - specular_base * coverage.a, 0) + reflection.rgb,
  // coverage being the (blurred) reflection colour, whose alpha is the share
  // of the lobe the trace found.
  virtual Image combine(const Image& base, const Image& reflection, Combine mode,
                        const Image* specular_base, const Image* coverage) = 0;
  Image combine(const Image& base, const Image& reflection, Combine mode) {
    return combine(base, reflection, mode, nullptr, nullptr);
  }
  // G-buffers (position, normal, specular) from view-space triangles; see raster.h.
  virtual GBufferImages rasterize(const RasterInputs& in) = 0;
};

// The CPU reference backend. threads = 0: one per hardware thread.
std::unique_ptr<Backend> make_cpu_backend(int threads = 0);

// Check a buffer's size and that it is non-empty; the name goes in the error.
void require_image(const Image& img, const char* name);
void require_same_size(const Image& a, const char* a_name, const Image& b, const char* b_name);
// Everything Backend::trace checks before it runs: buffer sizes, options, projection.
void require_trace_inputs(const TraceInputs& in, const TraceOptions& opt);
// What Backend::specular_weight and Backend::cone_blur check, on every backend.
void require_specular_weight_inputs(const Image& position, const Image& normal, const Image& specular,
                                    const Mat4& projection);
void require_cone_blur_inputs(const Image& color, const Image& uv, const Image& specular);

// Each pixel's cone_lod_at() as a one-channel image in r (g, b, a zero):
// what a compositor outside the core needs to blur a reflection it samples
// itself the way cone_blur would. Checks its inputs as cone_blur does.
Image cone_lod(const Image& uv, const Image& specular);
// The checks every backend's reflection / combine make before they run.
void require_reflection_inputs(const Image& color, const Image* blurred, const Image& specular,
                               const Image* weight);
void require_combine_inputs(const Image& base, const Image& reflection, Combine mode,
                            const Image* specular_base, const Image* coverage);

}  // namespace glint
