// The scene's triangles as an indexed mesh in view space, for marches that
// trace them (the exact march).
#pragma once
#include <cstdint>
#include <vector>

namespace glint {

struct TriangleMesh {
  std::vector<float> vertices;     // N * 3: x, y, z in view space
  std::vector<int32_t> triangles;  // M * 3: indices into vertices
};

// Throws InvalidArgument("mesh", ...) for sizes that are not whole vertices
// or triangles, out-of-range indices or non-finite vertices.
void validate(const TriangleMesh& mesh);

}  // namespace glint
