// The pyramid's base level, one row at a time, in the form the AVX2 version
// (hiz_base_avx2.cpp) takes it: plain pointers, since that file shares no
// inline code with the rest of the library. march_hiz.cpp's base_range() is
// the scalar rule and explains it.
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

}  // namespace glint::cpu
