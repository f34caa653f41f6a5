// The pyramid's base level and its plane normals, the G-buffer half of the
// reuse of rays and the pixels' own rays, one row at a time, in the form the
// AVX2 versions (hiz_base_avx2.cpp, hiz_planes_avx2.cpp, hiz_reuse_avx2.cpp,
// hiz_rays_avx2.cpp) take them: plain pointers, since those files share no
// inline code with the rest of the library. march_hiz.cpp's base_range()
// and make_ray(), hiz_reuse.cpp's reuse_surface() and hiz_planes.cpp's
// plane_normal() are the scalar rules and explain them.
#pragma once
#include <cstddef>

namespace glint::cpu {

// Row y of an image `width` x `height`, each pointer at the row's first
// texel: position (4 floats a texel), plane normals (3), the back layer (4,
// or null), seen flags (a byte), and out (nearest, farthest) pairs.
struct BaseRow {
  const float* position = nullptr;
  const float* planes = nullptr;
  const float* back = nullptr;
  const unsigned char* seen = nullptr;
  const float* inv = nullptr;  // HizCamera::inv
  float thickness = 0.0f;
  float footprint_spread = 0.0f;  // hiz::kFootprintSpread
  int width = 0, height = 0, y = 0;
  float* out = nullptr;
};

// base_range() of texels [0, n) of the row, n the width rounded down to a
// multiple of 8, bit for bit; returns n. Only where the CPU has AVX2
// (hiz_walk_available(WalkIsa::Avx2)).
int hiz_base_row_avx2(const BaseRow& row);

// Row y of the plane normals: position rows y - 2 .. y + 2 and their seen
// bytes (null for rows off the image), each at the row's first texel; the
// shading normal's row y (4 floats a texel); out, 3 floats a texel.
struct PlaneRow {
  const float* position[5] = {};
  const unsigned char* seen[5] = {};
  const float* normal = nullptr;
  float* out = nullptr;
};

// texel_seen() of texels [0, n) of a position row (4 floats a texel) as bytes
// (1 seen, 0 not), eight at a time: n a multiple of 8. Only where the CPU has
// AVX2.
void hiz_seen_row_avx2(const float* position, int n, unsigned char* out);

// plane_normal() of texels [x_begin, x_end) of the row, bit for bit, eight at
// a time: x_end - x_begin a multiple of 8, and x_begin >= 2, x_end <= width - 2
// (the row's neighbours two texels away lie inside). Only where the CPU has
// AVX2.
void hiz_plane_normals_row_avx2(const PlaneRow& row, int x_begin, int x_end);

// Row y of the second pass of the reuse of rays: the position, shading
// normal and specular rows y - 1, y and y + 1 (4 floats a texel, each at the
// row's first texel; specular null without a specular buffer, every row
// null where off the image), and a byte per texel out.
struct ReuseRow {
  const float* position[3] = {};
  const float* normal[3] = {};
  const float* specular[3] = {};
  int y = 0;
  float depth_share = 0.0f;  // hiz::kReuseDepth
  float cos2 = 0.0f;         // hiz::kReuseCos * hiz::kReuseCos
  unsigned char* out = nullptr;
};

// reuse_surface() of texels [x_begin, x_end) of the row as bytes (1 true, 0
// false; 0 for the first pass's texels), bit for bit, eight at a time:
// x_end - x_begin a multiple of 8, x_begin >= 1, x_end <= width - 1, and on
// an odd row both rows around it on the image. Only where the CPU has AVX2.
void hiz_reuse_row_avx2(const ReuseRow& row, int x_begin, int x_end);

// What march_hiz.cpp's Ray holds: everything about a ray that does not change
// along its walk (march_hiz.cpp says what each field is).
struct RayFields {
  float f0[2], d[2];   // start pixel coordinates and end - start
  float a0[3], da[3];  // A(0), A(1) - A(0): the view point times B
  float b0, db;        // B(0), B(1) - B(0): 1 / clip w
  float t_end;         // where the line leaves the image, or 1
  float inv[2];        // 1 / d, 0 where d is 0
  float nudge[2];      // hiz::kCellNudge along each axis the line moves on
};

// The pixels of row y whose own rays are made (make_ray()): the position and
// shading normal rows (4 floats a texel, at the row's first texel), the
// projection in float and in double (row-major), and MarchSetup's eye.
struct RayRow {
  const float* position = nullptr;
  const float* normal = nullptr;
  const float* proj = nullptr;
  const double* projd = nullptr;
  int eye_kind = 0;  // EyeKind: 0 origin, 1 point, 2 direction
  float eye[3] = {0.0f, 0.0f, 0.0f};
  float max_distance = 0.0f;
  float cell_nudge = 0.0f;  // hiz::kCellNudge
  int width = 0, height = 0, y = 0;
  // For the outline samples (subpixel_ray()): two floats a ray, its offset
  // from the pixel's centre in pixels; null for the pixels' own rays. Then
  // also the plane normals' row (3 floats a texel), HizCamera::inv and
  // hiz::kFootprintSpread.
  const float* offset = nullptr;
  const float* planes = nullptr;
  const float* inv = nullptr;
  float footprint_spread = 0.0f;
};

// make_ray() of pixels xs[0 .. n) of the row, or subpixel_ray() where
// `offset` is set, eight at a time: made[k] 1 with rays[k] its ray bit for
// bit, 0 where the pixel has no ray. Only where the CPU has AVX2.
void hiz_pixel_rays_avx2(const RayRow& row, const int* xs, int n, RayFields* rays, unsigned char* made);

}  // namespace glint::cpu
