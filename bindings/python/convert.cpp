#include "convert.h"

#include <algorithm>
#include <cstring>
#include <system_error>
#include <thread>
#include <vector>

#include "glint/errors.h"
#include "glint/options.h"

namespace glint::py {

namespace {

std::string shape_of(const pyb::array& a) {
  std::string s = "(";
  for (pyb::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string dtype_of(const pyb::array& a) { return pyb::str(a.dtype()).cast<std::string>(); }

pyb::array as_array(const pyb::handle& obj, const char* name) {
  if (!pyb::isinstance<pyb::array>(obj))
    throw InvalidArgument(name, "expected a numpy array, got " +
                                    pyb::str(pyb::type::of(obj).attr("__name__")).cast<std::string>());
  return pyb::reinterpret_borrow<pyb::array>(obj);
}

// A frame's G-buffer is three 33 MB copies at 1080p: one thread cannot move
// that at the memory's pace, two (or more) get closer. Small images in one go.
void copy_floats(float* dst, const float* src, size_t n) {
  constexpr size_t kSplitFloats = size_t{1} << 20;
  const unsigned hw = std::thread::hardware_concurrency();
  const size_t parts = n < kSplitFloats ? 1 : std::min<size_t>(hw == 0 ? 1 : hw, 4);
  if (parts <= 1) {
    std::memcpy(dst, src, n * sizeof(float));
    return;
  }
  const size_t step = (n + parts - 1) / parts;
  std::vector<std::thread> pool;
  for (size_t k = 1; k < parts; ++k) {
    const size_t a = std::min(n, k * step), b = std::min(n, a + step);
    try {
      pool.emplace_back([=] { std::memcpy(dst + a, src + a, (b - a) * sizeof(float)); });
    } catch (const std::system_error&) {
      std::memcpy(dst + a, src + a, (b - a) * sizeof(float));  // no thread to be had: copy it here
    }
  }
  std::memcpy(dst, src, std::min(n, step) * sizeof(float));
  for (auto& t : pool) t.join();
}

}  // namespace

Image image_from_array(const pyb::handle& obj, const char* name, float fill_alpha, int min_channels) {
  pyb::array a = as_array(obj, name);
  if (!a.dtype().is(pyb::dtype::of<float>()))
    throw InvalidArgument(name, "expected dtype float32, got " + dtype_of(a));
  if (a.ndim() != 3 || a.shape(2) < min_channels || a.shape(2) > 4)
    throw InvalidArgument(name, "expected shape (H, W, " +
                                    (min_channels == 4 ? std::string("4") : std::to_string(min_channels) + " to 4") +
                                    "), got " + shape_of(a));
  const auto h = a.shape(0), w = a.shape(1), c = a.shape(2);
  if (h <= 0 || w <= 0) throw InvalidArgument(name, "expected a non-empty image, got shape " + shape_of(a));
  if (h > kMaxImageSide || w > kMaxImageSide)
    throw InvalidArgument(name, "expected at most " + std::to_string(kMaxImageSide) +
                                    " pixels a side, got shape " + shape_of(a));
  // Accept any strides (a transposed or sliced view) by going through a
  // C-contiguous copy only when needed.
  auto contiguous = pyb::array_t<float, pyb::array::c_style | pyb::array::forcecast>::ensure(a);
  Image img = Image::uninitialized(static_cast<int>(w), static_cast<int>(h));  // every float set below
  const float* src = contiguous.data();
  if (c == 4) {
    copy_floats(img.data.data(), src, img.data.size());
  } else if (c == 3) {  // the usual normal buffer: a loop the compiler unrolls, not one per channel
    const size_t n = img.pixel_count();
    float* dst = img.data.data();
    for (size_t i = 0; i < n; ++i) {
      dst[i * 4] = src[i * 3];
      dst[i * 4 + 1] = src[i * 3 + 1];
      dst[i * 4 + 2] = src[i * 3 + 2];
      dst[i * 4 + 3] = fill_alpha;
    }
  } else {
    const size_t n = img.pixel_count();
    for (size_t i = 0; i < n; ++i) {
      for (pyb::ssize_t k = 0; k < c; ++k) img.data[i * 4 + k] = src[i * c + k];
      for (pyb::ssize_t k = c; k < 4; ++k) img.data[i * 4 + k] = (k == 3) ? fill_alpha : 0.0f;
    }
  }
  return img;
}

std::pair<int, int> array_size(const pyb::handle& obj) {
  if (!pyb::isinstance<pyb::array>(obj)) return {0, 0};
  const auto a = pyb::reinterpret_borrow<pyb::array>(obj);
  if (a.ndim() != 3 || a.shape(0) < 1 || a.shape(1) < 1 || a.shape(0) > kMaxImageSide ||
      a.shape(1) > kMaxImageSide)
    return {0, 0};
  return {static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0))};
}

uint64_t binding_bytes(uint64_t pixels, int images, int outputs) {
  return pixels * 16 * static_cast<uint64_t>(images + 1 + outputs);
}

pyb::array_t<float> array_from_image(Image&& img) {
  // The capsule owns the moved buffer and frees it with the array.
  auto pixels = std::make_unique<PixelBuffer>(std::move(img.data));
  float* data = pixels->data();
  pyb::capsule owner(pixels.get(), [](void* p) { delete static_cast<PixelBuffer*>(p); });
  pixels.release();
  return pyb::array_t<float>({static_cast<pyb::ssize_t>(img.height), static_cast<pyb::ssize_t>(img.width),
                              static_cast<pyb::ssize_t>(4)},
                             data, owner);
}

Mat4 matrix_from_array(const pyb::handle& obj, const char* name) {
  pyb::array a = as_array(obj, name);
  const bool f32 = a.dtype().is(pyb::dtype::of<float>());
  const bool f64 = a.dtype().is(pyb::dtype::of<double>());
  if (!f32 && !f64) throw InvalidArgument(name, "expected dtype float32 or float64, got " + dtype_of(a));
  if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4)
    throw InvalidArgument(name, "expected shape (4, 4), got " + shape_of(a));
  auto d = pyb::array_t<double, pyb::array::c_style | pyb::array::forcecast>::ensure(a);
  Mat4 m;
  for (int i = 0; i < 16; ++i) m.m[i] = d.data()[i];
  return m;
}

Mat4 projection_from_array(const pyb::handle& obj) {
  Mat4 m = matrix_from_array(obj, "projection");
  validate_projection(m);
  return m;
}

std::vector<float> vertices_from_array(const pyb::handle& obj, const char* name) {
  pyb::array v = as_array(obj, name);
  if (!v.dtype().is(pyb::dtype::of<float>()) || v.ndim() != 2 || v.shape(1) != 3)
    throw InvalidArgument(name, "expected vertices float32 of shape (N, 3), got " + dtype_of(v) + " " + shape_of(v));
  auto vc = pyb::array_t<float, pyb::array::c_style | pyb::array::forcecast>::ensure(v);
  return std::vector<float>(vc.data(), vc.data() + vc.size());
}

TriangleMesh mesh_from_arrays(const pyb::handle& vertices, const pyb::handle& triangles, const char* vertices_name,
                              const char* triangles_name) {
  TriangleMesh m;
  m.vertices = vertices_from_array(vertices, vertices_name);
  pyb::array f = as_array(triangles, triangles_name);
  if (!f.dtype().is(pyb::dtype::of<int32_t>()) || f.ndim() != 2 || f.shape(1) != 3)
    throw InvalidArgument(triangles_name, "expected triangles int32 of shape (M, 3), got " + dtype_of(f) + " " +
                                              shape_of(f));
  auto fc = pyb::array_t<int32_t, pyb::array::c_style | pyb::array::forcecast>::ensure(f);
  m.triangles.assign(fc.data(), fc.data() + fc.size());
  validate(m);
  return m;
}

std::optional<TriangleMesh> mesh_from_arg(const pyb::handle& obj) {
  if (obj.is_none()) return std::nullopt;
  if (std::optional<TriangleMesh> kept = mesh_from_exact_scene(obj)) return kept;
  if (!pyb::isinstance<pyb::tuple>(obj) || pyb::len(obj) != 2)
    throw InvalidArgument("mesh", "expected a tuple (vertices, triangles) or an ExactScene, got " +
                                      pyb::str(pyb::type::of(obj).attr("__name__")).cast<std::string>());
  pyb::tuple t = pyb::reinterpret_borrow<pyb::tuple>(obj);
  return mesh_from_arrays(t[0], t[1], "mesh", "mesh");
}

pyb::str lenient_str(const std::string& text) {
  PyObject* s = PyUnicode_DecodeUTF8(text.data(), static_cast<Py_ssize_t>(text.size()), "backslashreplace");
  if (!s) throw pyb::error_already_set();
  return pyb::reinterpret_steal<pyb::str>(s);
}

}  // namespace glint::py
