// Specular weight and cone blur on the CPU, in the operation order of
// shaders/specular_weight.frag and shaders/cone_blur.frag so that the two
// backends agree to rounding.
#include "look.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "glint/brdf.h"
#include "glint/material.h"
#include "glint/stages.h"
#include "parallel.h"

namespace glint::cpu {
namespace {

inline bool finite_f(float v) { return v - v == 0.0f; }
inline float clamp01(float v) { return v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v); }

// One level of the cone blur's chain from the level below: each texel the
// mean of the 2x2 block under it (the last row or column repeated when the
// level below has an odd size of 1).
Image reduce(const Image& src, int threads) {
  Image dst(std::max(1, src.width / 2), std::max(1, src.height / 2));
  parallel_rows(0, dst.height, threads, [&](int y) {
    const int y0 = 2 * y, y1 = std::min(2 * y + 1, src.height - 1);
    for (int x = 0; x < dst.width; ++x) {
      const int x0 = 2 * x, x1 = std::min(2 * x + 1, src.width - 1);
      const float *a = src.px(x0, y0), *b = src.px(x1, y0), *c = src.px(x0, y1), *d = src.px(x1, y1);
      float* o = dst.px(x, y);
      for (int k = 0; k < 4; ++k) o[k] = ((a[k] + b[k]) + (c[k] + d[k])) * 0.25f;
    }
  });
  return dst;
}

// Bilinear at (u, v) in [0, 1] on one level, clamp to edge: GL_LINEAR's rule,
// written out with texelFetch in the shader.
void bilinear(const Image& img, float u, float v, float out[4]) {
  const float tx = u * static_cast<float>(img.width) - 0.5f;
  const float ty = v * static_cast<float>(img.height) - 0.5f;
  const float fx = std::floor(tx), fy = std::floor(ty);
  const float ax = tx - fx, ay = ty - fy;
  const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
  const int x0 = std::clamp(ix, 0, img.width - 1), x1 = std::clamp(ix + 1, 0, img.width - 1);
  const int y0 = std::clamp(iy, 0, img.height - 1), y1 = std::clamp(iy + 1, 0, img.height - 1);
  const float *a = img.px(x0, y0), *b = img.px(x1, y0), *c = img.px(x0, y1), *d = img.px(x1, y1);
  for (int k = 0; k < 4; ++k) {
    const float bottom = a[k] * (1.0f - ax) + b[k] * ax;
    const float top = c[k] * (1.0f - ax) + d[k] * ax;
    out[k] = bottom * (1.0f - ay) + top * ay;
  }
}

}  // namespace

Image specular_weight(const Image& position, const Image& normal, const Image& specular,
                      const Mat4& projection, int threads) {
  const CameraEye eye = camera_eye(projection);
  const float* table = env_brdf_table().data();  // built once, before the workers share it
  // Zeroed a row at a time by the workers, not by one thread up front.
  Image out = Image::uninitialized(position.width, position.height);
  parallel_rows(0, out.height, threads, [&](int y) {
    std::fill(out.px(0, y), out.px(0, y) + static_cast<size_t>(out.width) * 4, 0.0f);
    for (int x = 0; x < out.width; ++x) {
      const float* p = position.px(x, y);
      const float* s = specular.px(x, y);
      if (!texel_seen(p) || !is_reflective(s)) continue;
      const float* n = normal.px(x, y);
      if (!finite_f(n[0]) || !finite_f(n[1]) || !finite_f(n[2])) continue;
      const float nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
      if (nn == 0.0f) continue;
      // The incident direction as the march uses it (cpu/ray.cpp read_origin).
      float d[3];
      incident_toward(eye, p, d);
      const float dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
      if (!(dd > 0.0f) || !finite_f(dd)) continue;
      const float inv_n = 1.0f / std::sqrt(nn), inv_d = 1.0f / std::sqrt(dd);
      const float dn = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
      const float n_dot_v = clamp01(-(dn * inv_n * inv_d));
      float* o = out.px(x, y);
      split_sum_weight(table, s, n_dot_v, o);
      o[3] = (o[0] + o[1] + o[2]) / 3.0f;
    }
  });
  return out;
}

Image cone_blur(const Image& color, const Image& uv, const Image& specular, const MirrorScale* mirror,
                int threads) {
  // Level 0 is `color` itself; the levels above are built here.
  std::vector<Image> above;
  std::vector<const Image*> chain{&color};
  while (chain.back()->width > 1 || chain.back()->height > 1) {
    above.push_back(reduce(*chain.back(), threads));
    chain.clear();
    chain.push_back(&color);
    for (const Image& level : above) chain.push_back(&level);
  }
  const int last = static_cast<int>(chain.size()) - 1;
  const float w = static_cast<float>(color.width), h = static_cast<float>(color.height);
  Image out = color;
  parallel_rows(0, out.height, threads, [&](int y) {
    for (int x = 0; x < out.width; ++x) {
      const float* s = specular.px(x, y);
      const float* t = uv.px(x, y);
      if (!is_reflective(s)) continue;
      const float full = cone_lod_at(x, y, out.width, out.height, t, s, mirror);
      if (!(full > 0.0f)) continue;  // within one texel: the colour itself
      const float cx = static_cast<float>(x) + 0.5f, cy = static_cast<float>(y) + 0.5f;
      const float lod = std::min(full, static_cast<float>(last));
      const int k0 = static_cast<int>(lod);
      const int k1 = std::min(k0 + 1, last);
      const float f = lod - static_cast<float>(k0);
      float c0[4], c1[4];
      bilinear(*chain[k0], cx / w, cy / h, c0);
      bilinear(*chain[k1], cx / w, cy / h, c1);
      float* o = out.px(x, y);
      for (int k = 0; k < 4; ++k) o[k] = c0[k] * (1.0f - f) + c1[k] * f;
    }
  });
  return out;
}

}  // namespace glint::cpu
