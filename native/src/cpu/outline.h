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
// channel), a plain miss, a ray that came into an object by its hidden side
// (blocked="occluder", hit channel hiz::kEnteredHidden), or anything else (an
// occluder found late), which is left as it is.
enum class Report : unsigned char { Miss = 0, Hit = 1, Other = 2, Entered = 3 };
inline Report report_of(const float* o) {
  if (o[3] > 0.0f) return Report::Hit;
  if (o[3] == hiz::kEnteredHidden) return Report::Entered;
  return o[2] == 0.0f && o[3] == 0.0f ? Report::Miss : Report::Other;
}

// Whether reports a and b (report_of()'s bytes) meet at an outline a pixel's
// rays can resolve: a hit and a miss (the object's edge against what lies
// beyond), or a hit and a hidden side entered (the line on a reflected object
// where the side the camera sees gives way to the side it does not, such as
// the top of a floating sphere's reflection, which is a staircase at one ray
// a pixel). Written on bytes, with no branch, so that the search's row loop
// vectorises: {0, 1} is the one pair with xor 1 and or 1, {1, 3} the one with
// xor 2 and and 1.
inline bool opposite_reports(unsigned char a, unsigned char b) {
  const unsigned char x = static_cast<unsigned char>(a ^ b);
  return (x == 1 && (a | b) == 1) | (x == 2 && (a & b) == 1);
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
// by row: a hit beside a plain miss or a hidden side entered on the same
// surface, or the other way round (opposite_reports()), where the pixel's
// reflection is sharp (the cone blur's footprint at the hit within a pixel,
// given the specular buffer). `beside_hidden`, when given, gets a byte per
// listed pixel: 1 where the pixel or a 4-neighbour entered a hidden side
// (resolve_outline()'s `one_hit_uv`).
std::vector<std::vector<int>> outline_pixels(const TraceInputs& in, const Image& out, int threads,
                                             std::vector<std::vector<unsigned char>>* beside_hidden = nullptr);

// The pixel's report from its centre c and its k samples, the box filter of
// the k + 1: visibility is the hits' share, the uv their visibility-weighted
// mean. A hidden side entered counts as no hit here: the share it leaves is
// what composite_layers() gives the hidden side (settle_uncertain_shares(),
// glint/composite.h). Only where every hit lies within hiz::kReusePixels of
// the first (one object's outline) and nothing but hits and misses, or hits
// and hidden sides, was reported; elsewhere `o` keeps the centre's report.
// With `one_hit_uv` (a pixel beside a hidden side) the uv is the first hit's,
// not the mean: there the hits meet the object's rim, whose texels the engine
// blends with what is behind, and their mean falls between texels, where a
// read takes in that blend; one hit's uv is read as any hit's is, moved off
// the rim (glint/composite.h, read_inside_outlines()). `o` may be `c`.
void resolve_outline(const float* c, const float* samples, int k, float w, float h, float* o,
                     bool one_hit_uv = false);

}  // namespace glint::cpu
