// The scene's triangles for marches that trace them (the exact march).
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "glint/projection.h"

namespace glint {

class ExactScene;  // glint/exact_scene.h

// Either the arrays, in view space, from which the call builds a BVH of its
// own; or `scene`, whose BVH is kept between calls in a frame the camera
// does not move, with `view_to_world` taking view space into that frame (the
// arrays are then empty).
struct TriangleMesh {
  std::vector<float> vertices;     // N * 3: x, y, z in view space
  std::vector<int32_t> triangles;  // M * 3: indices into vertices
  std::shared_ptr<const ExactScene> scene;
  Mat4 view_to_world{{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}};
};

// Throws InvalidArgument("mesh", ...) for sizes that are not whole vertices
// or triangles, out-of-range indices or non-finite vertices.
void validate(const TriangleMesh& mesh);

}  // namespace glint
