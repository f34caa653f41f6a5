// The per-pixel ray marches of the CPU backend. Written in float32 with the
// same operation order as shaders/trace_*.frag so that CPU and GL agree.
#pragma once
#include <cmath>
#include <vector>

#include "glint/image.h"
#include "glint/options.h"
#include "glint/projection.h"
#include "glint/stages.h"
#include "parallel.h"

namespace glint::cpu {

// Everything a march needs that does not change from pixel to pixel.
struct MarchSetup {
  const Image* position = nullptr;
  const Image* normal = nullptr;
  // The view distance (-z) of every position texel, NaN where unseen. The
  // hit tests need nothing else, and a quarter of the bytes keeps the march's
  // scattered reads in cache; the full texel is read once, for the last probe.
  const float* view_distance = nullptr;
  float proj[16];   // row-major float copy of the projection
  double projd[16];  // the same in double, for near-plane clipping
  ProjectionKind kind = ProjectionKind::Perspective;
  TraceOptions opt;
  // Where the camera looks from, for the incident direction of each pixel.
  // Origin: the seed's normalize(position). Point: normalize(position - eye).
  // Direction: an orthographic camera's rays are all parallel to `eye`.
  using Eye = EyeKind;
  Eye eye_kind = Eye::Origin;
  float eye[3] = {0.0f, 0.0f, 0.0f};
};


// `view_distance` must hold position.width * position.height floats filled by
// fill_view_distance, and outlive the setup.
MarchSetup make_setup(const Image& position, const Image& normal, const Mat4& projection,
                      const TraceOptions& opt, const float* view_distance);
// Row y of the view-distance buffer (see MarchSetup::view_distance).
void fill_view_distance(const Image& position, int y, float* out);
// The whole view-distance buffer, rows in parallel.
std::vector<float> view_distances(const Image& position, int threads);

// FIX 3 (docs/conventions.md): nearest texel at floor(uv * size); outside the image or on an
// unseen texel is a miss. Returns the texel's index (or -1 on a miss) and
// its view distance (0 on a miss: the seed's cleared texel).
inline long fetch_texel(const MarchSetup& s, float u, float v, float& scene_vd) {
  const Image& pos = *s.position;
  int x = 0, y = 0;
  if (pos.texel_at(u * static_cast<float>(pos.width), v * static_cast<float>(pos.height), x, y)) {
    const long i = static_cast<long>(y) * pos.width + x;
    const float vd = s.view_distance[i];
    if (vd == vd) {
      scene_vd = vd;
      return i;
    }
  }
  scene_vd = 0.0f;
  return -1;
}

// The full texel behind a fetch, (0, 0, 0, 0) for a miss.
inline void texel_at(const MarchSetup& s, long i, float out[4]) {
  if (i < 0) {
    out[0] = out[1] = out[2] = out[3] = 0.0f;
    return;
  }
  const float* p = s.position->data.data() + static_cast<size_t>(i) * 4;
  out[0] = p[0]; out[1] = p[1]; out[2] = p[2]; out[3] = p[3];
}

// A whole frame of a per-pixel march: what the seed and the linear march
// share. A template, so that each march's file inlines its own pixel.
template <class PerPixel>
Image trace_pixels(const TraceInputs& in, const TraceOptions& opt, int threads, PerPixel&& march) {
  Image out = Image::uninitialized(in.position.width, in.position.height);  // each march writes its pixel
  const std::vector<float> vd = view_distances(in.position, threads);
  const MarchSetup setup = make_setup(in.position, in.normal, in.projection, opt, vd.data());
  const Image* spec = in.specular;
  parallel_rows(0, out.height, threads, [&](int y) {
    for (int x = 0; x < out.width; ++x) {
      float* o = out.px(x, y);
      if (spec && !is_reflective(spec->px(x, y))) {  // the seed returns early here
        o[0] = o[1] = o[2] = o[3] = 0.0f;
        continue;
      }
      march(setup, x, y, o);
    }
  });
  return out;
}

}  // namespace glint::cpu
