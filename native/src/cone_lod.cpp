// cone_lod(): the cone blur's per-pixel level of detail as an image, for a
// compositor that samples the reflection colour itself (the Blender add-on's
// node group blends Gaussian levels by it; docs/addon.md).
#include "glint/stages.h"

#include "glint/errors.h"
#include "parallel.h"

namespace glint {

Image cone_lod(const Image& uv, const Image& specular) {
  require_image(uv, "uv");
  require_same_size(uv, "uv", specular, "specular");
  Image out(uv.width, uv.height);
  // Per frame at full size (2 M pixels at 1080p): on every core.
  parallel_rows(0, uv.height, 0, [&](int y) {
    for (int x = 0; x < uv.width; ++x) {
      const float* s = specular.px(x, y);
      out.px(x, y)[0] = is_reflective(s) ? cone_lod_at(x, y, uv.width, uv.height, uv.px(x, y), s) : 0.0f;
    }
  });
  return out;
}

}  // namespace glint
