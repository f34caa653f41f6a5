// glint_core.rasterize: G-buffers (position, normal, specular, and the
// back-face layer with its albedo) from a view-space triangle soup, on the
// CPU reference or the GL backend.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "convert.h"
#include "glint/backend.h"
#include "glint/errors.h"
#include "glint/memory.h"
#include "glint/raster.h"
#include "glint/schema.h"

namespace glint::py {

namespace {

using namespace pybind11::literals;

std::string shape_string(const pyb::array& a) {
  std::string s = "(";
  for (pyb::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

pyb::array require_array(const pyb::handle& obj, const char* name) {
  if (!pyb::isinstance<pyb::array>(obj))
    throw InvalidArgument(name, "expected a numpy array, got " +
                                    pyb::str(pyb::type::of(obj).attr("__name__")).cast<std::string>());
  return pyb::reinterpret_borrow<pyb::array>(obj);
}

// Checks ndim and the fixed trailing sizes (-1 in `dims` = any length);
// `expected` is the shape as the docs write it, for the message.
void require_shape(const pyb::array& a, const char* name, const std::vector<pyb::ssize_t>& dims,
                   const char* expected) {
  bool ok = a.ndim() == static_cast<pyb::ssize_t>(dims.size());
  for (size_t i = 0; ok && i < dims.size(); ++i) ok = dims[i] < 0 || a.shape(i) == dims[i];
  if (!ok)
    throw InvalidArgument(name, std::string("expected shape ") + expected + ", got " + shape_string(a));
}

// Per-triangle data is large: take float32 only, so that nothing is
// silently converted (and copied) on every frame.
std::vector<float> float32_values(const pyb::handle& obj, const char* name,
                                  const std::vector<pyb::ssize_t>& dims, const char* expected) {
  pyb::array a = require_array(obj, name);
  if (!a.dtype().is(pyb::dtype::of<float>()))
    throw InvalidArgument(name, "expected dtype float32, got " + pyb::str(a.dtype()).cast<std::string>());
  require_shape(a, name, dims, expected);
  auto c = pyb::array_t<float, pyb::array::c_style | pyb::array::forcecast>::ensure(a);
  return std::vector<float>(c.data(), c.data() + c.size());
}

// Index arrays: int32, or int64 within int32's range (numpy's default int).
std::vector<int32_t> int32_values(const pyb::handle& obj, const char* name, const char* expected) {
  pyb::array a = require_array(obj, name);
  require_shape(a, name, {-1}, expected);
  if (a.dtype().is(pyb::dtype::of<int32_t>())) {
    auto c = pyb::array_t<int32_t, pyb::array::c_style | pyb::array::forcecast>::ensure(a);
    return std::vector<int32_t>(c.data(), c.data() + c.size());
  }
  if (!a.dtype().is(pyb::dtype::of<int64_t>()))
    throw InvalidArgument(name, "expected dtype int32, got " + pyb::str(a.dtype()).cast<std::string>());
  auto c = pyb::array_t<int64_t, pyb::array::c_style | pyb::array::forcecast>::ensure(a);
  std::vector<int32_t> out(static_cast<size_t>(c.size()));
  for (size_t i = 0; i < out.size(); ++i) {
    const int64_t v = c.data()[i];
    if (v < std::numeric_limits<int32_t>::min() || v > std::numeric_limits<int32_t>::max())
      throw InvalidArgument(name, "entry " + std::to_string(i) + " is " + std::to_string(v) +
                                      ", outside the int32 range");
    out[i] = static_cast<int32_t>(v);
  }
  return out;
}

pyb::dict py_rasterize(const pyb::handle& positions, const pyb::handle& normals,
                       const pyb::handle& material_index, const pyb::handle& materials,
                       const pyb::handle& projection, int width, int height, const pyb::handle& uvs,
                       const pyb::handle& tangents, const pyb::handle& material_normal_map,
                       const pyb::handle& normal_maps, bool back_layer,
                       const pyb::handle& material_albedo, const std::string& backend, int threads,
                       double memory_limit_mb) {
  const bool back_albedo = !material_albedo.is_none();
  // Before anything is allocated: the albedo only exists for the back layer.
  if (back_albedo && !back_layer) throw InvalidArgument("material_albedo", "needs back_layer=True");
  // Before any copy: the triangles' copies (positions, normals, index, uvs,
  // tangents: 4 * (9 + 9 + 1 + 6 + 12) bytes each) and the backend's own
  // buffers, whose images become the output arrays.
  if (width >= 1 && height >= 1 && width <= kMaxImageSide && height <= kMaxImageSide) {
    uint64_t tris = 0;
    if (pyb::isinstance<pyb::array>(positions)) {
      const auto a = pyb::reinterpret_borrow<pyb::array>(positions);
      if (a.ndim() >= 1) tris = static_cast<uint64_t>(a.shape(0));
    }
    require_memory(tris * 4 * 37 + raster_bytes(width, height, tris, back_layer, back_albedo,
                                                backend != "cpu"),
                   "rasterize at " + std::to_string(width) + "x" + std::to_string(height),
                   memory_limit_mb);
  }
  // T is the length of positions; the other per-triangle arrays must match it.
  Mesh mesh;
  mesh.positions = float32_values(positions, "positions", {-1, 3, 3}, "(T, 3, 3)");
  const pyb::ssize_t t = static_cast<pyb::ssize_t>(mesh.positions.size() / 9);
  const std::string tn = std::to_string(t);
  mesh.normals = float32_values(normals, "normals", {t, 3, 3}, ("(T, 3, 3) with T = " + tn).c_str());
  mesh.material = int32_values(material_index, "material_index", ("(T,) with T = " + tn).c_str());
  if (static_cast<pyb::ssize_t>(mesh.material.size()) != t)
    throw InvalidArgument("material_index", "expected shape (T,) with T = " + tn +
                                                " (the triangles in positions), got (" +
                                                std::to_string(mesh.material.size()) + ",)");
  if (!uvs.is_none())
    mesh.uvs = float32_values(uvs, "uvs", {t, 3, 2}, ("(T, 3, 2) with T = " + tn).c_str());
  if (!tangents.is_none())
    mesh.tangents = float32_values(tangents, "tangents", {t, 3, 4}, ("(T, 3, 4) with T = " + tn).c_str());

  // The material table is small: float64 is accepted too.
  pyb::array mat = require_array(materials, "materials");
  if (!mat.dtype().is(pyb::dtype::of<float>()) && !mat.dtype().is(pyb::dtype::of<double>()))
    throw InvalidArgument("materials", "expected dtype float32 or float64, got " +
                                           pyb::str(mat.dtype()).cast<std::string>());
  require_shape(mat, "materials", {-1, 4}, "(M, 4) = (specular r, g, b, shininess)");
  auto mat_values = pyb::array_t<float, pyb::array::c_style | pyb::array::forcecast>::ensure(mat);
  std::vector<Material> table(static_cast<size_t>(mat.shape(0)));
  for (size_t k = 0; k < table.size(); ++k) {
    const float* row = mat_values.data() + 4 * k;
    table[k].specular[0] = row[0];
    table[k].specular[1] = row[1];
    table[k].specular[2] = row[2];
    table[k].shininess = row[3];
  }
  if (!material_normal_map.is_none()) {
    const std::vector<int32_t> maps = int32_values(material_normal_map, "material_normal_map", "(M,)");
    if (maps.size() != table.size())
      throw InvalidArgument("material_normal_map",
                            "expected shape (M,) with M = " + std::to_string(table.size()) +
                                " (the rows of materials), got (" + std::to_string(maps.size()) + ",)");
    for (size_t k = 0; k < maps.size(); ++k) table[k].normal_map = maps[k];
  }
  if (back_albedo) {
    // Small like the material table: float64 is accepted too. Finite and
    // >= 0 is checked by validate(), with the row.
    pyb::array alb = require_array(material_albedo, "material_albedo");
    if (!alb.dtype().is(pyb::dtype::of<float>()) && !alb.dtype().is(pyb::dtype::of<double>()))
      throw InvalidArgument("material_albedo", "expected dtype float32 or float64, got " +
                                                   pyb::str(alb.dtype()).cast<std::string>());
    const std::string expected =
        "(M, 3) = (albedo r, g, b) with M = " + std::to_string(table.size()) + " (the rows of materials)";
    require_shape(alb, "material_albedo", {static_cast<pyb::ssize_t>(table.size()), 3}, expected.c_str());
    auto values = pyb::array_t<float, pyb::array::c_style | pyb::array::forcecast>::ensure(alb);
    for (size_t k = 0; k < table.size(); ++k)
      for (int c = 0; c < 3; ++c) table[k].albedo[c] = values.data()[3 * k + c];
  }

  std::vector<Image> images;
  if (!pyb::isinstance<pyb::sequence>(normal_maps) || pyb::isinstance<pyb::array>(normal_maps) ||
      pyb::isinstance<pyb::str>(normal_maps))
    throw InvalidArgument("normal_maps", "expected a sequence of float32 (h, w, 3 or 4) arrays");
  const pyb::sequence seq = pyb::reinterpret_borrow<pyb::sequence>(normal_maps);
  for (size_t k = 0; k < seq.size(); ++k) {
    const std::string name = "normal_maps[" + std::to_string(k) + "]";
    images.push_back(image_from_array(seq[k], name.c_str(), 1.0f, 3));
  }

  const Mat4 proj = projection_from_array(projection);
  RasterInputs in{mesh, table, images, proj, width, height};
  in.back_layer = back_layer;
  in.back_albedo = back_albedo;
  in.memory_limit_mb = memory_limit_mb;
  validate(in);
  auto be = get_backend(backend, threads);
  GBufferImages g;
  {
    pyb::gil_scoped_release release;
    g = be->rasterize(in);
  }
  pyb::dict out;
  out["position"] = array_from_image(std::move(g.position));
  out["normal"] = array_from_image(std::move(g.normal));
  out["specular"] = array_from_image(std::move(g.specular));
  if (back_layer) out["back_position"] = array_from_image(std::move(g.back_position));
  if (back_albedo) out["back_albedo"] = array_from_image(std::move(g.back_albedo));
  return out;
}

}  // namespace

void bind_raster(pyb::module_& m) {
  m.def("rasterize", &py_rasterize, "positions"_a, "normals"_a, "material_index"_a, "materials"_a,
        "projection"_a, "width"_a, "height"_a, pyb::kw_only(), "uvs"_a = pyb::none(),
        "tangents"_a = pyb::none(), "material_normal_map"_a = pyb::none(),
        "normal_maps"_a = pyb::tuple(), "back_layer"_a = false, "material_albedo"_a = pyb::none(),
        "backend"_a = schema::backend.initial_name,
        "threads"_a = schema::threads.initial_int(),
        "memory_limit_mb"_a = 0.0,
        "G-buffers from view-space triangles (Blender camera space, -Z forward).\n"
        "positions, normals: float32 (T, 3, 3); material_index: int32 (T,);\n"
        "materials: (M, 4) = (specular r, g, b, shininess 0..MAX_SHININESS);\n"
        "uvs (T, 3, 2), tangents (T, 3, 4) (xyz + bitangent sign), material_normal_map int32 (M,)\n"
        "(-1 = none) and normal_maps (float32 (h, w, 3|4) images) for tangent-space normal maps.\n"
        "Returns dict(position, normal, specular) of float32 (height, width, 4), plus\n"
        "back_position with back_layer=True: the nearest back-facing surface behind each\n"
        "pixel's own (w = 0 where none), for trace(back_position=...).\n"
        "material_albedo: float32/float64 (M, 3) diffuse albedo per material (finite, >= 0),\n"
        "only with back_layer=True; adds back_albedo = (albedo r, g, b of that back surface's\n"
        "material, 1) where back_position is set, zeros elsewhere, to shade a reflection that\n"
        "meets an object's hidden side with its own colour. Row 0 at the bottom;\n"
        "pixels no triangle covers are all zeros. Triangles with a non-finite corner are skipped.\n"
        "memory_limit_mb: as for trace(); a request over it raises MemoryLimitExceeded.");
}

}  // namespace glint::py
