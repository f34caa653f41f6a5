// The CPU reference rasterizer behind CpuBackend::rasterize, and the coverage
// primitive it is built on (exposed so tests can count how often a pixel is
// covered, which the depth-tested G-buffer cannot show).
#pragma once
#include <cstdint>
#include <vector>

#include "glint/raster.h"

namespace glint::cpu {

// Validates `in`, then rasterizes it. threads = 0: one per hardware thread.
GBufferImages rasterize(const RasterInputs& in, int threads);

// How many of the (near/far-clipped) triangles cover each pixel centre of a
// width x height image, row 0 at the bottom. Same clipping, snapping and tie
// rule as rasterize(), but no depth test. For tests.
std::vector<int> coverage_count(const std::vector<float>& positions, const Mat4& projection,
                                int width, int height);

}  // namespace glint::cpu
