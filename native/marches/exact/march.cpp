// The "exact" march's row of the table of marches. Its code is
// march_exact.cpp beside it (Embree, and the ExactScene of
// glint/exact_scene.h); it has no GL form.
#include "exact.h"
#include "glint/marches.h"

namespace glint {

MarchInfo glint_march_exact() {
  MarchInfo m;
  m.name = "exact";
  m.description =
      "The ground truth: each pixel's mirror ray traced against the scene's triangles (Embree), "
      "reported where the camera sees the hit; runs on the CPU whatever the backend";
  m.knobs = {{"max_distance", "length of the reflected ray, view units: the first hit within it counts"},
             {"antialias",
              "extra rays from inside a pixel on a reflection's outline (a hit beside a miss), whose share "
              "of hits becomes its visibility: 0 one ray per pixel, up to 4"}};
  m.needs_mesh = true;
  // Each triangle copied into Embree (48 bytes) with its plane (32), and
  // Embree's BVH about 4 node bytes per triangle more (robust, medium).
  m.scratch_per_triangle = 320;
  // Antialiased outlines: a report byte per pixel and the outline lists.
  m.scratch_per_pixel = 2;
  m.cpu = &cpu::trace_exact;
  return m;
}

}  // namespace glint
