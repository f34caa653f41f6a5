// The pipeline's stages, each a plain function of images, and the Backend
// interface that every implementation (CPU reference, OpenGL) provides, so a
// stage can be run and compared on either.
//
//   G-buffer (position, normal, specular)
//     -> trace            reflected uv + visibility  (u, v, vis, vis)
//     -> reflection_color colour at the reflected uv, premultiplied by visibility
//     -> box_blur         (2 * size + 1)^2 box of the reflection colour
//     -> reflection       mix(colour, blurred, roughness) * specular amount
//     -> combine          the reflection over the base image
#pragma once
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
// True when a position texel counts as "seen": w > 0 and every channel finite.
inline bool texel_seen(const float* p) {
  return p[3] > 0.0f && p[0] - p[0] == 0.0f && p[1] - p[1] == 0.0f && p[2] - p[2] == 0.0f &&
         p[3] - p[3] == 0.0f;
}

// A pixel is reflective when its specular amount is positive (and finite).
bool is_reflective(const float* spec);

// Material specular, the book's mapping: Blender Internal hardness 1..511,
// shininess = hardness / 4 (511 -> 127.75), alpha = clamp(shininess / 127.75, 0, 1).
constexpr float kMaxShininess = 127.75f;
inline float shininess_from_hardness(float hardness) { return hardness / 4.0f; }
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
  // mix(color, blurred, roughness) * specular amount; 0 where the amount <= 0.
  virtual Image reflection(const Image& color, const Image& blurred, const Image& specular) = 0;
  virtual Image combine(const Image& base, const Image& reflection, Combine mode) = 0;
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

}  // namespace glint
