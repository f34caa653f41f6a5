// Antialiased outlines (docs/marches.md): what the CPU marches that antialias
// share. After every pixel has its own report, the pixels on a reflection's
// outline are found, each traces a few more rays from inside its footprint
// (each march its own way), and the rays' reports are box-filtered into the
// pixel's. hiz's GL passes (hiz_outline_*.comp) port the same rules.
#pragma once
#include <vector>

#include "glint/image.h"
#include "glint/schema.h"
#include "glint/stages.h"

namespace glint::cpu {

// The rotated grid (glint/schema.h): sample k's offset from the pixel's
// centre, in pixels. Four rows and four columns of a 4x4 grid.
constexpr float kAaOffset[4][2] = {{-hiz::kAntialiasNear, -hiz::kAntialiasFar},
                                   {hiz::kAntialiasFar, -hiz::kAntialiasNear},
                                   {hiz::kAntialiasNear, hiz::kAntialiasFar},
                                   {-hiz::kAntialiasFar, hiz::kAntialiasNear}};

// A report as the outline test sees it: a hit (visibility in the fourth
// channel), a plain miss, or anything else (a blocked ray's occluder), which
// is left as it is.
enum class Report : unsigned char { Miss, Hit, Other };
inline Report report_of(const float* o) {
  if (o[3] > 0.0f) return Report::Hit;
  return o[2] == 0.0f && o[3] == 0.0f ? Report::Miss : Report::Other;
}

// report_of() of `width` pixels of a row of reports (4 floats a pixel), as
// bytes.
void report_row(const float* o, int width, unsigned char* bytes);

// Whether normals n and m (any length) lie within hiz::kReuseCos of each other.
inline bool normals_agree(const float* n, const float* m) {
  const float nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  const float d = n[0] * m[0] + n[1] * m[1] + n[2] * m[2];
  const float mm = m[0] * m[0] + m[1] * m[1] + m[2] * m[2];
  return d > 0.0f && d * d >= hiz::kReuseCos * hiz::kReuseCos * nn * mm;
}

// Whether pixel (qx, qy) reflects and lies on the same smooth surface as the
// pixel at position p with normal n: normals within hiz::kReuseCos, view
// distances within hiz::kReuseDepth of each other (hiz's reuse of rays asks
// the same).
bool same_surface(const TraceInputs& in, const float* p, const float* n, int qx, int qy);

// The pixels of `out` (every pixel's own report) on a reflection's outline,
// by row: a hit beside a plain miss on the same surface, or the other way
// round, where the pixel's reflection is sharp (the cone blur's footprint at
// the hit within a pixel, given the specular buffer).
std::vector<std::vector<int>> outline_pixels(const TraceInputs& in, const Image& out, int threads);

// The pixel's report from its centre c and its k samples, the box filter of
// the k + 1: visibility is the hits' share, the uv their visibility-weighted
// mean. Only where every hit lies within hiz::kReusePixels of the first (one
// object's outline against a miss) and nothing else was reported; elsewhere
// `o` keeps the centre's report. `o` may be `c`.
void resolve_outline(const float* c, const float* samples, int k, float w, float h, float* o);

}  // namespace glint::cpu
