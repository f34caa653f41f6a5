// numpy <-> glint::Image and friends, shared by every binding file.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "glint/image.h"
#include "glint/mesh.h"
#include "glint/projection.h"

namespace glint::py {

namespace pyb = pybind11;

// A float32 [H, W, C] array (C = 3 or 4, or C = `min_channels`..4) as an RGBA
// Image; a 3-channel input gets `fill_alpha` in the 4th channel. Anything
// else raises ValueError naming `name`.
Image image_from_array(const pyb::handle& obj, const char* name, float fill_alpha = 1.0f,
                       int min_channels = 3);
// Width and height of an [H, W, C] array, read without converting it, for the
// memory budget; (0, 0) for anything the conversion will refuse anyway.
std::pair<int, int> array_size(const pyb::handle& obj);
// Bytes the bindings add to a request of `pixels`: `images` RGBA copies made
// from the arguments plus one temporary (a strided array is made contiguous
// first), and `outputs` float32 [H, W, 4] arrays returned.
uint64_t binding_bytes(uint64_t pixels, int images, int outputs);
// An RGBA Image as a float32 [H, W, 4] array that takes over its pixels (no
// copy: at 1920x1080 a copy is 33 MB of fresh pages, faults and zeroing
// included, on every call).
pyb::array_t<float> array_from_image(Image&& img);

// Text that came from a file or quotes one (EXR layer and attribute names, error
// messages naming them) as a Python str: bytes that are not UTF-8 become
// backslash escapes instead of a UnicodeDecodeError in place of the answer.
pyb::str lenient_str(const std::string& text);
// None, (vertices float32 [N, 3], triangles int32 [M, 3]) as a validated
// mesh, or an ExactScene (seen from a camera) as one; anything else raises
// ValueError naming `mesh`.
std::optional<TriangleMesh> mesh_from_arg(const pyb::handle& obj);
// The two arrays of a mesh, validated; ValueError naming the argument.
std::vector<float> vertices_from_array(const pyb::handle& obj, const char* name);
TriangleMesh mesh_from_arrays(const pyb::handle& vertices, const pyb::handle& triangles, const char* vertices_name,
                              const char* triangles_name);
// glint_core.ExactScene or ExactView (bind_exact.cpp) as the mesh a trace
// reads; nullopt for anything else.
std::optional<TriangleMesh> mesh_from_exact_scene(const pyb::handle& obj);
// Registers ExactScene and ExactView: declared here, beside what mesh_from_arg
// takes from it, so that module.cpp adds only the call.
void bind_exact(pyb::module_& m);
// A 4x4 float32/float64 array (rows as printed) as a Mat4; ValueError naming
// `name` for any other array.
Mat4 matrix_from_array(const pyb::handle& obj, const char* name);
// The same, validated as a projection.
Mat4 projection_from_array(const pyb::handle& obj);

}  // namespace glint::py
