// Checks on RasterInputs shared by every backend. Error messages use the
// Python keyword names of glint_core.rasterize, since that is what users see.
#include <cmath>
#include <limits>
#include <string>

#include "glint/errors.h"
#include "glint/options.h"
#include "glint/raster.h"
#include "glint/stages.h"

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

void validate(const RasterInputs& in) {
  if (in.width < 1 || in.width > kMaxImageSide)
    throw InvalidArgument("width", "expected 1.." + std::to_string(kMaxImageSide) + ", got " +
                                       std::to_string(in.width));
  if (in.height < 1 || in.height > kMaxImageSide)
    throw InvalidArgument("height", "expected 1.." + std::to_string(kMaxImageSide) + ", got " +
                                        std::to_string(in.height));
  validate_projection(in.projection);

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
