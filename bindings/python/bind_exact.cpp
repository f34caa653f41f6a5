// glint_core.ExactScene: the exact march's triangles with a BVH kept between
// calls (glint/exact_scene.h), and ExactView, a scene seen from one camera;
// either is what trace()'s mesh= takes in place of (vertices, triangles).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "convert.h"
#include "glint/errors.h"
#include "glint/exact_scene.h"
#include "glint/memory.h"
#include "glint/mesh.h"

namespace pyb = pybind11;
using namespace pybind11::literals;

namespace glint::py {
namespace {

// A scene and the camera's place in its frame.
struct ExactView {
  std::shared_ptr<ExactScene> scene;
  Mat4 view_to_world;
};

pyb::dict report_dict(const BvhReport& r) { return pyb::dict("bvh"_a = to_string(r.work), "ms"_a = r.milliseconds); }

// Before any copy, as every entry point does: the BVH, the planes and
// Embree's copy of the triangles are what a large scene costs.
void require_scene_memory(const pyb::handle& triangles, double memory_limit_mb) {
  if (!pyb::isinstance<pyb::array>(triangles)) return;  // the conversion refuses it
  const auto a = pyb::reinterpret_borrow<pyb::array>(triangles);
  if (a.ndim() != 2) return;
  const uint64_t count = static_cast<uint64_t>(a.shape(0));
  require_memory(trace_bytes(0, 0, March::Exact, false, count),
                 "ExactScene of " + std::to_string(count) + " triangles", memory_limit_mb);
}

std::shared_ptr<ExactScene> make_scene(const pyb::handle& vertices, const pyb::handle& triangles, int threads,
                                       double memory_limit_mb) {
  if (threads < 0) throw InvalidArgument("threads", "expected 0 (every core) or more, got " + std::to_string(threads));
  require_scene_memory(triangles, memory_limit_mb);
  const TriangleMesh mesh = mesh_from_arrays(vertices, triangles, "vertices", "triangles");
  pyb::gil_scoped_release release;
  return std::make_shared<ExactScene>(mesh, threads);
}

pyb::dict update_scene(ExactScene& scene, const pyb::handle& vertices, const pyb::handle& triangles,
                       double memory_limit_mb) {
  BvhReport r;
  if (triangles.is_none()) {
    const std::vector<float> v = vertices_from_array(vertices, "vertices");
    pyb::gil_scoped_release release;
    r = scene.update_vertices(v);
  } else {
    require_scene_memory(triangles, memory_limit_mb);
    const TriangleMesh mesh = mesh_from_arrays(vertices, triangles, "vertices", "triangles");
    pyb::gil_scoped_release release;
    r = scene.update(mesh);
  }
  return report_dict(r);
}

std::string scene_repr(const ExactScene& s) {
  const BvhReport r = s.last_update();
  char ms[32];
  std::snprintf(ms, sizeof ms, "%.1f", r.milliseconds);
  return "<glint_core.ExactScene: " + std::to_string(s.triangle_count()) + " triangles, " +
         std::to_string(s.vertex_count()) + " vertices; bvh: " + to_string(r.work) + " (" + ms + " ms)>";
}

pyb::array_t<double> matrix_array(const Mat4& m) {
  pyb::array_t<double> a({4, 4});
  for (int i = 0; i < 16; ++i) a.mutable_data()[i] = m.m[i];
  return a;
}

}  // namespace

std::optional<TriangleMesh> mesh_from_exact_scene(const pyb::handle& obj) {
  TriangleMesh m;
  if (pyb::isinstance<ExactView>(obj)) {
    const ExactView& v = obj.cast<const ExactView&>();
    m.scene = v.scene;
    m.view_to_world = v.view_to_world;
    return m;
  }
  if (pyb::isinstance<ExactScene>(obj)) {
    m.scene = obj.cast<std::shared_ptr<ExactScene>>();
    return m;
  }
  return std::nullopt;
}

void bind_exact(pyb::module_& m) {
  // Both classes first: each one's signatures name the other.
  pyb::class_<ExactView> view(m, "ExactView",
                              "An ExactScene seen from one camera (ExactScene.seen_from): pass it as mesh=.");
  pyb::class_<ExactScene, std::shared_ptr<ExactScene>> scene(
      m, "ExactScene",
      "The exact march's triangles with their BVH, kept between calls: build it once, pass\n"
      "mesh=scene.seen_from(camera_to_world) to trace(), composite_layers() or pipeline()\n"
      "every frame, and update() it when the vertices move. Its frame is the caller's: world\n"
      "space, so that a camera move changes only the matrix, never the BVH (or view space, for\n"
      "mesh=scene). Traces on one scene may run at once from many threads; update() waits for\n"
      "the running ones. docs/marches.md, 'The exact march'.");

  view.def_property_readonly("scene", [](const ExactView& v) { return v.scene; }, "The ExactScene.")
      .def_property_readonly(
          "view_to_world", [](const ExactView& v) { return matrix_array(v.view_to_world); },
          "float64 [4, 4]: view space into the scene's frame.");

  scene
      .def(pyb::init(&make_scene), "vertices"_a, "triangles"_a, pyb::kw_only(), "threads"_a = 0,
           "memory_limit_mb"_a = 0.0,
           "Builds the BVH over vertices float32 [N, 3] and triangles int32 [M, 3], in a frame the\n"
           "camera does not move. threads: Embree's build and refit threads (0: every core).\n"
           "memory_limit_mb as for trace().")
      .def("update", &update_scene, "vertices"_a, "triangles"_a = pyb::none(), pyb::kw_only(),
           "memory_limit_mb"_a = 0.0,
           "New vertex positions: the BVH is refit (same triangles), rebuilt (other triangles,\n"
           "or another vertex count) or kept (the very same vertices and triangles).\n"
           "triangles=None: the scene's own, and vertices must be as many as before.\n"
           "Returns last_update.")
      .def(
          "seen_from",
          [](const std::shared_ptr<ExactScene>& s, const pyb::handle& view_to_world) {
            ExactView v{s, matrix_from_array(view_to_world, "view_to_world")};
            validate_view_to_world(v.view_to_world);
            return v;
          },
          "view_to_world"_a,
          "This scene seen from a camera: what mesh= takes. view_to_world: float32/float64 4x4, the\n"
          "camera's matrix into the scene's frame (Blender's camera.matrix_world), affine.")
      .def_property_readonly(
          "last_update", [](const ExactScene& s) { return report_dict(s.last_update()); },
          "{'bvh': 'built' | 'refit' | 'reused', 'ms': float}: what the constructor or the last\n"
          "finished update() did to the BVH, and its time (the wait for running traces left out);\n"
          "reading it never waits for an update in progress.")
      .def_property_readonly("vertex_count", &ExactScene::vertex_count, "Vertices in the scene.")
      .def_property_readonly("triangle_count", &ExactScene::triangle_count, "Triangles in the scene.")
      .def("__repr__", &scene_repr);
}

}  // namespace glint::py
