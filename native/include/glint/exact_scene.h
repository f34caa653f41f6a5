// The exact march's triangles with their BVH, kept between calls.
//
// Building Embree's BVH over a million triangles costs more than tracing a
// frame against it, and an animation's geometry mostly stays put while the
// camera moves. An ExactScene holds the triangles in a frame of the caller's
// choosing that the camera does not move (world space, in Blender), so that a
// camera move changes only the matrix a trace passes (TriangleMesh::scene and
// view_to_world, glint/mesh.h), never the BVH. When the vertices move with the
// same triangles (object transforms, deformation) update() refits the BVH;
// other triangles rebuild it. docs/marches.md, "The exact march".
//
// Thread safety: any number of traces may run on one scene at once; update()
// waits for the traces running and holds off new ones while it changes the BVH,
// so a trace always sees one whole state of the scene, before or after.
#pragma once
#include <cstddef>
#include <memory>
#include <vector>

#include "glint/projection.h"

namespace glint {

struct TriangleMesh;  // glint/mesh.h

// What a build or an update did to the BVH.
enum class BvhWork {
  Built,   // a new BVH over the triangles: a new scene, or new triangles
  Refit,   // the same triangles with new vertex positions: the BVH's boxes refitted
  Reused,  // vertices and triangles as they were: nothing done
};
const char* to_string(BvhWork work);

struct BvhReport {
  BvhWork work = BvhWork::Built;
  // The whole call but the wait for traces running: checks, copies, planes, Embree.
  double milliseconds = 0.0;
};

class ExactScene {
 public:
  // Builds the BVH over `mesh`'s arrays (validate(mesh): InvalidArgument
  // "mesh" when they are malformed). `threads`: Embree's build and refit
  // threads, 0 for every core.
  explicit ExactScene(const TriangleMesh& mesh, int threads = 0);
  ~ExactScene();
  ExactScene(const ExactScene&) = delete;
  ExactScene& operator=(const ExactScene&) = delete;

  // New vertex positions for the same triangles: InvalidArgument
  // "vertices" unless there are as many as before, all finite.
  BvhReport update_vertices(const std::vector<float>& vertices);
  // A whole new mesh: a refit when its triangles are the scene's, a rebuild
  // when they are not (or the vertex count changed).
  BvhReport update(const TriangleMesh& mesh);
  // What the constructor or the last finished update did, and the counts it
  // left; these three never wait for an update in progress.
  BvhReport last_update() const;
  size_t vertex_count() const;
  size_t triangle_count() const;

  // The march's side of the scene (native/marches/exact/march_exact.cpp).
  class Impl;
  const Impl& impl() const { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

// Throws InvalidArgument("view_to_world", ...) unless `m` is finite, affine
// (last row 0, 0, 0, 1) and invertible: the camera's own matrix (Blender's
// camera.matrix_world), which takes view space into the scene's frame.
void validate_view_to_world(const Mat4& m);

}  // namespace glint
