// The Backend interface that every implementation (CPU reference, OpenGL)
// provides, so a stage can be run and compared on either, and picking one by
// name: "cpu", "gl" or "auto" (GL when a context can be made, CPU otherwise).
// Backends are cached: the GL context is made once per process and reused.
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
#include <memory>
#include <string>

#include "glint/image.h"
#include "glint/options.h"
#include "glint/projection.h"
#include "glint/raster.h"

namespace glint {

// What the trace stage needs to know about which pixels matter. With a
// specular buffer, pixels whose specular amount is zero are not traced and
// report (0, 0, 0, 0); without one every seen pixel is traced.
struct TriangleMesh;  // glint/mesh.h

struct MirrorScale;  // glint/material.h

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
  // 2 * ray length in pixels (|uv - pixel centre|) * cone_tan(alpha), no
  // wider than a flat mirror's where `mirror` is given (cone_lod_at()), read
  // trilinearly from a 2x2 box mip chain of `color` (all four channels).
  // Pixels with alpha 0, zero visibility or no reflection keep their colour.
  virtual Image cone_blur(const Image& color, const Image& uv, const Image& specular,
                          const MirrorScale* mirror) = 0;
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

// Throws InvalidArgument("backend", ...) for an unknown name and
// BackendUnavailable when "gl" was asked for and cannot run here.
std::shared_ptr<Backend> get_backend(const std::string& name, int threads = 0);

// True when this build has the GL backend compiled in (GLINT_WITH_GL).
bool gl_compiled_in();

#ifdef GLINT_HAVE_GL
// Defined by the GL backend (native/src/gl). Throws BackendUnavailable.
std::shared_ptr<Backend> make_gl_backend();
#endif

}  // namespace glint
