// The out-of-line part of glint/material.h: the specular buffer's alpha, and
// cone_lod(), the cone blur's per-pixel level of detail as an image, for a
// compositor that samples the reflection colour itself (the Blender add-on's
// node group blends Gaussian levels by it; docs/addon.md).
#include "glint/material.h"

#include "glint/errors.h"
#include "glint/validation.h"
#include "parallel.h"

namespace glint {

float shininess_to_alpha(float shininess) {
  const float a = shininess / kMaxShininess;
  if (!(a > 0.0f)) return 0.0f;
  return a - a == 0.0f ? a : 1.0f;  // +inf: a mirror, not a finite gloss
}

MirrorScale mirror_scale(const Image& position, const Mat4& projection) {
  MirrorScale m;
  m.position = &position;
  m.eye = camera_eye(projection);
  m.pixels_per_unit = static_cast<float>(0.5 * position.height * std::fabs(projection(1, 1)));
  for (int k = 0; k < 4; ++k) m.w_row[k] = static_cast<float>(projection(3, k));
  return m;
}

Image cone_lod(const Image& uv, const Image& specular, const MirrorScale* mirror) {
  require_image(uv, "uv");
  require_same_size(uv, "uv", specular, "specular");
  if (mirror && mirror->position) require_same_size(uv, "uv", *mirror->position, "position");
  Image out(uv.width, uv.height);
  // Per frame at full size (2 M pixels at 1080p): on every core.
  parallel_rows(0, uv.height, 0, [&](int y) {
    for (int x = 0; x < uv.width; ++x) {
      const float* s = specular.px(x, y);
      out.px(x, y)[0] = is_reflective(s) ? cone_lod_at(x, y, uv.width, uv.height, uv.px(x, y), s, mirror) : 0.0f;
    }
  });
  return out;
}

}  // namespace glint
