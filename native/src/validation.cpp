// The checks every stage's inputs pass before it runs, whichever backend runs
// it (glint/validation.h, and validate(RasterInputs) of glint/raster.h).
// Error messages use the Python keyword names, since that is what users see.
#include "glint/validation.h"

#include <cmath>
#include <limits>
#include <string>

#include "glint/errors.h"
#include "glint/material.h"
#include "glint/marches.h"
#include "glint/mesh.h"
#include "glint/options.h"
#include "glint/raster.h"

namespace glint {

namespace {

void require_count(size_t have, size_t triangles, size_t per_triangle, const char* name,
                   const char* shape) {
  if (have != triangles * per_triangle)
    throw InvalidArgument(name, std::string("expected ") + shape + " with T = " +
                                    std::to_string(triangles) +
                                    " (the length of material_index), got " +
                                    std::to_string(have) + " values");
}

}  // namespace

void require_image(const Image& img, const char* name) {
  if (img.width <= 0 || img.height <= 0)
    throw InvalidArgument(name, "expected a non-empty image, got " + std::to_string(img.width) +
                                    "x" + std::to_string(img.height));
  if (img.width > kMaxImageSide || img.height > kMaxImageSide)
    throw InvalidArgument(name, "expected at most " + std::to_string(kMaxImageSide) +
                                    " pixels a side, got " + std::to_string(img.width) + "x" +
                                    std::to_string(img.height));
  if (img.data.size() != img.pixel_count() * 4)
    throw InvalidArgument(name, "pixel storage does not match its size");
}

void require_same_size(const Image& a, const char* a_name, const Image& b, const char* b_name) {
  require_image(b, b_name);
  if (a.width != b.width || a.height != b.height)
    throw InvalidArgument(b_name, std::string("expected the size of ") + a_name + " (" +
                                      std::to_string(a.width) + "x" + std::to_string(a.height) +
                                      "), got " + std::to_string(b.width) + "x" +
                                      std::to_string(b.height));
}

void require_trace_inputs(const TraceInputs& in, const TraceOptions& opt) {
  require_image(in.position, "position");
  require_same_size(in.position, "position", in.normal, "normal");
  if (in.specular) require_same_size(in.position, "position", *in.specular, "specular");
  if (in.back_position)
    require_same_size(in.position, "position", *in.back_position, "back_position");
  validate(opt);
  validate_projection(in.projection);
  const MarchInfo& info = march_info(opt.march);
  if (info.needs_mesh && !in.mesh)
    throw InvalidArgument("mesh", std::string("march \"") + info.name +
                                      "\" traces the scene's triangles: pass mesh=(vertices, triangles)");
}

void require_specular_weight_inputs(const Image& position, const Image& normal, const Image& specular,
                                    const Mat4& projection) {
  require_image(position, "position");
  require_same_size(position, "position", normal, "normal");
  require_same_size(position, "position", specular, "specular");
  validate_projection(projection);
}

void require_cone_blur_inputs(const Image& color, const Image& uv, const Image& specular,
                              const MirrorScale* mirror) {
  require_image(color, "reflection_color");
  require_same_size(color, "reflection_color", uv, "uv");
  require_same_size(color, "reflection_color", specular, "specular");
  if (mirror && mirror->position) require_same_size(color, "reflection_color", *mirror->position, "position");
}

void require_reflection_inputs(const Image& color, const Image* blurred, const Image& specular,
                               const Image* weight) {
  require_image(color, "reflection_color");
  if (blurred) require_same_size(color, "reflection_color", *blurred, "reflection_blur");
  require_same_size(color, "reflection_color", specular, "specular");
  if (weight) require_same_size(color, "reflection_color", *weight, "specular_weight");
}

void require_combine_inputs(const Image& base, const Image& reflection, Combine mode,
                            const Image* specular_base, const Image* coverage) {
  require_image(base, "color");
  require_same_size(base, "color", reflection, "reflection");
  if (!specular_base) return;
  if (mode != Combine::Over)
    throw InvalidArgument("specular_base", "is replaced only with combine=\"over\"");
  require_same_size(base, "color", *specular_base, "specular_base");
  if (!coverage) throw InvalidArgument("coverage", "is needed with specular_base");
  require_same_size(base, "color", *coverage, "coverage");
}

void validate(const RasterInputs& in) {
  if (in.width < 1 || in.width > kMaxImageSide)
    throw InvalidArgument("width", "expected 1.." + std::to_string(kMaxImageSide) + ", got " +
                                       std::to_string(in.width));
  if (in.height < 1 || in.height > kMaxImageSide)
    throw InvalidArgument("height", "expected 1.." + std::to_string(kMaxImageSide) + ", got " +
                                        std::to_string(in.height));
  validate_projection(in.projection);
  if (in.back_albedo && !in.back_layer)
    throw InvalidArgument("back_albedo", "needs back_layer: it is the back layer's material");

  const Mesh& mesh = in.mesh;
  const size_t t = mesh.triangle_count();
  // Triangle ids travel through int32 buffers (and GL's 32-bit indices).
  if (t > static_cast<size_t>(std::numeric_limits<int32_t>::max() / 3))
    throw InvalidArgument("material_index",
                          "expected at most " +
                              std::to_string(std::numeric_limits<int32_t>::max() / 3) +
                              " triangles, got " + std::to_string(t));
  require_count(mesh.positions.size(), t, 9, "positions", "shape (T, 3, 3)");
  require_count(mesh.normals.size(), t, 9, "normals", "shape (T, 3, 3)");

  const size_t m = in.materials.size();
  if (t > 0 && m == 0)
    throw InvalidArgument("materials", "expected at least one material, got shape (0, 4)");
  const size_t maps = in.normal_maps.size();
  for (size_t k = 0; k < m; ++k) {
    const Material& mat = in.materials[k];
    const float v[4] = {mat.specular[0], mat.specular[1], mat.specular[2], mat.shininess};
    for (float x : v) {
      if (!std::isfinite(x))
        throw InvalidArgument("materials", "expected finite values, row " + std::to_string(k) +
                                               " has " + std::to_string(x));
    }
    for (float x : mat.albedo) {
      if (!std::isfinite(x) || x < 0.0f)
        throw InvalidArgument("material_albedo", "expected finite values >= 0, row " +
                                                     std::to_string(k) + " has " + std::to_string(x));
    }
    if (mat.normal_map < -1 || mat.normal_map >= static_cast<int>(maps))
      throw InvalidArgument("material_normal_map",
                            "expected -1 (none) or an index into normal_maps (0.." +
                                std::to_string(static_cast<long long>(maps) - 1) + "), entry " +
                                std::to_string(k) + " is " + std::to_string(mat.normal_map));
  }
  for (size_t k = 0; k < maps; ++k) {
    const std::string name = "normal_maps[" + std::to_string(k) + "]";
    require_image(in.normal_maps[k], name.c_str());
  }

  bool needs_tangents = false;
  for (size_t i = 0; i < t; ++i) {
    const int32_t id = mesh.material[i];
    if (id < 0 || static_cast<size_t>(id) >= m)
      throw InvalidArgument("material_index",
                            "expected indices into materials (0.." +
                                std::to_string(static_cast<long long>(m) - 1) + "), entry " +
                                std::to_string(i) + " is " + std::to_string(id));
    if (in.materials[id].normal_map >= 0) needs_tangents = true;
  }
  // uvs and tangents are optional until a triangle's material has a normal
  // map; when given anyway they must still fit, to catch a shifted array.
  if (needs_tangents || !mesh.uvs.empty()) {
    if (mesh.uvs.empty())
      throw InvalidArgument("uvs", "expected shape (T, 3, 2): a material with a normal map is used");
    require_count(mesh.uvs.size(), t, 6, "uvs", "shape (T, 3, 2)");
  }
  if (needs_tangents || !mesh.tangents.empty()) {
    if (mesh.tangents.empty())
      throw InvalidArgument("tangents",
                            "expected shape (T, 3, 4): a material with a normal map is used");
    require_count(mesh.tangents.size(), t, 12, "tangents", "shape (T, 3, 4)");
  }
}

}  // namespace glint
