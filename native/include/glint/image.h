// The one buffer type every stage reads and writes.
#pragma once
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <new>
#include <utility>
#include <vector>

#include "glint/buffer_pool.h"

namespace glint {

// std::allocator with two changes for pixel buffers. A vector sized without a
// value leaves its floats uninitialised: an image a stage overwrites whole (a
// trace's output, a numpy array copied in) then costs its page faults alone,
// taken by the threads that write it, instead of a serial zeroing pass first.
// And buffers of kPoolMinBytes or more come from, and go back to, the buffer
// pool (glint/buffer_pool.h), so the next frame finds them already mapped.
template <class T>
struct PixelAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = PixelAllocator<U>;
  };
  using std::allocator<T>::allocator;
  T* allocate(std::size_t n) {
    if (n > std::numeric_limits<std::size_t>::max() / sizeof(T)) throw std::bad_array_new_length();
    if (n * sizeof(T) >= kPoolMinBytes) return static_cast<T*>(pool_allocate(n * sizeof(T)));
    return std::allocator<T>::allocate(n);
  }
  void deallocate(T* p, std::size_t n) noexcept {
    if (n * sizeof(T) >= kPoolMinBytes) return pool_deallocate(p, n * sizeof(T));
    std::allocator<T>::deallocate(p, n);
  }
  template <class U>
  void construct(U* p) noexcept(noexcept(::new (static_cast<void*>(p)) U)) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

using PixelBuffer = std::vector<float, PixelAllocator<float>>;

// An RGBA float32 image, pixels stored [row][col][channel], C-contiguous.
// Row 0 is the BOTTOM row (OpenGL and Blender order), so pixel (x, y) has its
// centre at uv ((x + 0.5) / width, (y + 0.5) / height) and an Image maps 1:1
// onto an RGBA32F texture. Every stage works on four channels: inputs with
// three are widened once at the boundary instead of branching per pixel.
struct Image {
  int width = 0;
  int height = 0;
  PixelBuffer data;

  Image() = default;
  Image(int w, int h, float fill = 0.0f)
      : width(w), height(h), data(static_cast<size_t>(w) * static_cast<size_t>(h) * 4, fill) {}

  // Pixels left unset: only for an image whose every pixel is written next.
  static Image uninitialized(int w, int h) {
    Image img;
    img.width = w;
    img.height = h;
    img.data.resize(static_cast<size_t>(w) * static_cast<size_t>(h) * 4);
    return img;
  }

  bool empty() const { return width <= 0 || height <= 0; }
  size_t pixel_count() const { return static_cast<size_t>(width) * static_cast<size_t>(height); }
  float* px(int x, int y) { return data.data() + (static_cast<size_t>(y) * width + x) * 4; }
  const float* px(int x, int y) const {
    return data.data() + (static_cast<size_t>(y) * width + x) * 4;
  }

  // The texel (i, j) holding the point (x, y), in pixels; false off the image,
  // NaN included. The bounds are checked on the floats, before converting:
  // a float beyond int's range converts with undefined behaviour, and rays
  // and uvs from outside input can carry any value.
  bool texel_at(float x, float y, int& i, int& j) const {
    const float fx = std::floor(x), fy = std::floor(y);
    if (!(fx >= 0.0f && fy >= 0.0f && fx < static_cast<float>(width) && fy < static_cast<float>(height)))
      return false;
    i = static_cast<int>(fx);
    j = static_cast<int>(fy);
    return true;
  }
};

}  // namespace glint
