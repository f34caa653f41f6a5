// The "hiz" march's pyramid on the CPU (its walk is hiz_walk.h's), and its
// entry points on both backends. The GL backend runs the same steps in
// hiz_base.frag, hiz_reduce.frag and trace_hiz.frag (gl_passes.cpp);
// docs/hiz.md explains the method.
#pragma once
#include <cstddef>
#include <vector>

#include "glint/image.h"
#include "glint/options.h"
#include "glint/projection.h"
#include "glint/schema.h"
#include "glint/stages.h"
#include "hiz_walk.h"

namespace glint {

// The hiz march at resolution <= kHizReuseResolution traces every other pixel
// of every other row first, and each other pixel only where those traced
// around it disagree (docs/hiz.md, "Reusing neighbours' rays"). Both
// backends decide by this.
constexpr float kHizReuseResolution = hiz::kReuseResolution;
inline bool hiz_reuses_rays(const TraceOptions& o) {
  return o.march == March::Hiz && o.resolution <= kHizReuseResolution;
}

namespace gl {
class GlState;
// The march on the GL backend (gl_passes.cpp): the pyramid, then the trace,
// reusing rays as the CPU does. The row's gl_trace.
Image trace_hiz(GlState& gl, const TraceInputs& in, const TraceOptions& opt);
}  // namespace gl

}  // namespace glint

namespace glint::cpu {

// Level sizes follow OpenGL's mip rule, floor(size / 2) and at least 1, so
// that the CPU and GL pyramids have the same cells. The last cell of a row or
// column covers what an odd size leaves over (hiz_walk_scalar()).
struct HizPyramid {
  int levels = 0;
  std::vector<int> width, height;
  std::vector<size_t> offset;  // first cell of each level, in cells
  // Two floats per cell: the nearest view distance of any surface in it
  // (over each texel's whole footprint, not only its centre), and the
  // farthest view distance its surfaces reach once their thickness is added.
  // Cells with nothing seen hold (+inf, -inf) and never overlap a ray.
  // Not zero-filled: every cell is written once, by the worker threads.
  PixelBuffer range;

  size_t index(int level, int i, int j) const {
    return offset[level] + static_cast<size_t>(j) * width[level] + i;
  }
  const float* cell(int level, int i, int j) const { return range.data() + index(level, i, j) * 2; }
  float* cell(int level, int i, int j) { return range.data() + index(level, i, j) * 2; }
};

// The inverse projection as floats, row-major: what the base level needs to
// find the depth a texel's tangent plane has at the texel's corners.
struct HizCamera {
  float inv[16];
};
HizCamera hiz_camera(const Mat4& projection);

// xyz per texel, row-major. Not zero-filled (a PixelBuffer sized without a
// value): build_hiz_pyramid() writes every texel once on the worker threads.
struct HizPlanes {
  int width = 0, height = 0;
  PixelBuffer xyz;
  const float* px(int x, int y) const { return xyz.data() + (static_cast<size_t>(y) * width + x) * 3; }
  float* px(int x, int y) { return xyz.data() + (static_cast<size_t>(y) * width + x) * 3; }
};

// Whether each texel of rows [y0, y0 + rows) is seen (texel_seen()), a byte
// each: the plane normals ask it of up to eight neighbours per texel, and
// the base of each texel, so a block of rows asks each texel once. Eight
// texels at a time where `isa` is the AVX2 walk's (hiz_base.h).
struct SeenRows {
  int y0 = 0, width = 0;
  std::vector<unsigned char> bytes;
  bool at(int x, int y) const { return bytes[static_cast<size_t>(y - y0) * width + x] != 0; }
};
void fill_seen_rows(const Image& position, int y0, int y1, SeenRows& out, WalkIsa isa);

// The normal of each texel's tangent plane, for the pyramid's base and the
// texel test (never the ray's direction, which follows the shading normal):
// the surface's geometric normal from the position buffer, so that a normal
// map does not tilt a flat surface into bumps. Per axis, the difference to
// the seen neighbour whose view distance is closer to the texel's own (so a
// silhouette does not bend it); the shading normal where an axis has no seen
// neighbour or the texel none usable. xyz unit length, facing the side the
// shading normal is on. Row y of them, into `out` (sized to the image);
// `seen` covers rows y - 2 .. y + 2 (those inside the image). Eight texels
// at a time where `isa` is the AVX2 walk's (hiz_base.h), the same normals.
void hiz_plane_normals_row(const Image& position, const Image& normal, const SeenRows& seen, int y,
                           HizPlanes& out, WalkIsa isa);

// The pyramid, and into `planes` the plane normals above that its base and
// the walk use: both in one pass over the G-buffer, a row of normals and
// then the same row of the base while the row is in the cache. `normal` is
// the shading normal. Per-texel thickness: back_position's view distance
// minus the front's where a back surface is known and behind, else
// `thickness`. The base level's rows go eight texels at a time where `isa` is
// the AVX2 walk's (hiz_base.h), by the scalar rule otherwise: the same cells.
HizPyramid build_hiz_pyramid(const Image& position, const Image& normal, const Image* back_position,
                             const HizCamera& cam, float thickness, int threads, HizPlanes& planes,
                             WalkIsa isa);

// With `resolution` <= 0.5 a trace reuses rays (docs/hiz.md): the pixels
// it does not trace first take their neighbours' answers where those lie on
// their surface and agree. The surface half of that test for every pixel of
// row y, a byte each (1: the pixel has a ray and its traced neighbours lie on
// its surface; 0 also for the pixels traced first), into `ok` (a row's
// width); eight pixels at a time where `isa` is the AVX2 walk's
// (hiz_base.h), the same bytes.
void hiz_reuse_surface_row(const TraceInputs& in, int y, WalkIsa isa, unsigned char* ok);

// Answers every pixel (x0, y), (x0 + step, y), ... of a pass that does not
// walk, and lists in xs, in order, those that do: a pixel that passed
// hiz_reuse_surface_row() (`reusable`, on the second pass; null on the first)
// takes its neighbours' reports where they agree; the rest are misses that a
// walk's hit overwrites, and walk where they reflect. hiz_reuse.cpp.
void hiz_row_jobs(const TraceInputs& in, Image& out, int y, int x0, int step, const unsigned char* reusable,
                  std::vector<int>& xs);

// The pixel's own ray (march_hiz.cpp's make_ray()) of pixels (xs[k], y) for
// k in [0, n): made[k] 1 with rays[k] set, 0 where the pixel has no ray.
// Eight pixels at a time where `isa` is the AVX2 walk's (hiz_base.h), the
// same rays bit for bit.
struct MarchSetup;
struct RayFields;
void hiz_pixel_rays(const MarchSetup& s, int y, const int* xs, int n, WalkIsa isa, RayFields* rays,
                    unsigned char* made);

// The antialiased outlines' rays (march_hiz.cpp's subpixel_ray()): ray k from
// pixel (xs[k], y), offsets[2k] and offsets[2k + 1] pixels off its centre,
// from where the view ray through that point meets the texel's tangent
// plane; made and rays as hiz_pixel_rays(), the same rays bit for bit on
// AVX2.
void hiz_sample_rays(const MarchSetup& s, const HizPlanes& planes, const HizCamera& cam, int y, const int* xs,
                     const float* offsets, int n, WalkIsa isa, RayFields* rays, unsigned char* made);

// The whole frame on the CPU, with the walk hiz_walk_default() picks: the
// `cpu` entry of the march's row (march.cpp).
Image trace_hiz(const TraceInputs& in, const TraceOptions& opt, int threads);
// The same with the given walk, which must be available: the tests hold the
// walks to the same answers.
Image trace_hiz(const TraceInputs& in, const TraceOptions& opt, int threads, WalkIsa isa);

}  // namespace glint::cpu
