// The one buffer type every stage reads and writes.
#pragma once
#include <cstddef>
#include <vector>

namespace glint {

// An RGBA float32 image, pixels stored [row][col][channel], C-contiguous.
// Row 0 is the BOTTOM row (OpenGL and Blender order), so pixel (x, y) has its
// centre at uv ((x + 0.5) / width, (y + 0.5) / height) and an Image maps 1:1
// onto an RGBA32F texture. Every stage works on four channels: inputs with
// three are widened once at the boundary instead of branching per pixel.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<float> data;

  Image() = default;
  Image(int w, int h, float fill = 0.0f)
      : width(w), height(h), data(static_cast<size_t>(w) * static_cast<size_t>(h) * 4, fill) {}

  bool empty() const { return width <= 0 || height <= 0; }
  size_t pixel_count() const { return static_cast<size_t>(width) * static_cast<size_t>(height); }
  float* px(int x, int y) { return data.data() + (static_cast<size_t>(y) * width + x) * 4; }
  const float* px(int x, int y) const {
    return data.data() + (static_cast<size_t>(y) * width + x) * 4;
  }
};

}  // namespace glint
