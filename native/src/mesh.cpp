#include "glint/mesh.h"

#include <cmath>
#include <string>

#include "glint/errors.h"

namespace glint {

void validate(const TriangleMesh& mesh) {
  if (mesh.vertices.size() % 3 != 0)
    throw InvalidArgument("mesh", "expected vertices of shape [N, 3], got " +
                                      std::to_string(mesh.vertices.size()) + " floats");
  if (mesh.triangles.size() % 3 != 0)
    throw InvalidArgument("mesh", "expected triangles of shape [M, 3], got " +
                                      std::to_string(mesh.triangles.size()) + " indices");
  const long long n = static_cast<long long>(mesh.vertices.size() / 3);
  for (size_t k = 0; k < mesh.triangles.size(); ++k) {
    const long long i = mesh.triangles[k];
    if (i < 0 || i >= n)
      throw InvalidArgument("mesh", "triangle " + std::to_string(k / 3) + " indexes vertex " +
                                        std::to_string(i) + ", expected 0.." + std::to_string(n - 1));
  }
  for (size_t k = 0; k < mesh.vertices.size(); ++k)
    if (!std::isfinite(mesh.vertices[k]))
      throw InvalidArgument("mesh", "vertex " + std::to_string(k / 3) + " is not finite");
}

}  // namespace glint
