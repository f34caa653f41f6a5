// The per-pixel ray marches of the CPU backend. Written in float32 with the
// same operation order as shaders/trace_*.frag so that CPU and GL agree.
#pragma once
#include <vector>

#include "glint/image.h"
#include "glint/options.h"
#include "glint/projection.h"
#include "glint/stages.h"

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

// Writes (u, v, visibility, visibility) for pixel (x, y); (0, 0, 0, 0) where
// nothing was seen, the normal is zero, or the ray cannot be projected.
void march_seed(const MarchSetup& s, int x, int y, float out[4]);
void march_linear(const MarchSetup& s, int x, int y, float out[4]);


}  // namespace glint::cpu
