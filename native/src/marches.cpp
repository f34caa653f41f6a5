// The table of marches (glint/marches.h).
#include "glint/marches.h"

#include <string>

#include "cpu/trace.h"
#include "glint/errors.h"

namespace glint {

const std::vector<MarchInfo>& march_table() {
  // Adding a march: a row here, its CPU function in cpu/trace.h, its GL
  // program in shaders/ (or nullptr), and docs/marches.md.
  // Scratch: seed and linear keep one float view distance per texel; the hiz
  // pyramid is 2 floats per cell, 4/3 cells per texel, rounded up; the exact
  // march copies each triangle into Embree (48 bytes), keeps its plane (32)
  // and Embree's BVH takes about 4 node bytes per triangle more (robust, medium).
  static const std::vector<MarchInfo> table = {
      {March::Seed, "seed",
       "The seed chapter's two-pass march: a coarse pass over a share of the pixels, then bisection",
       {{"max_distance", "length of the reflected ray, view units; also fades the reflection"},
        {"resolution", "share of the pixels the ray crosses on screen that the coarse pass visits"},
        {"steps", "bisection iterations after the first coarse hit"},
        {"thickness", "how far behind the depth buffer a sample still counts as a hit, view units"}},
       false, 4, 0, false, &cpu::trace_seed, "trace_seed.frag"},
      {March::Linear, "linear",
       "The book's older march: fixed view-space steps, stepping back and approaching after a hit",
       {{"max_distance", "length of the reflected ray, view units"},
        {"steps", "view-space steps along the ray (max_distance / steps each)"},
        {"thickness", "how far behind the depth buffer a sample still counts as a hit, view units"}},
       false, 4, 0, false, &cpu::trace_linear, "trace_linear.frag"},
      {March::Hiz, "hiz",
       "Min/max depth pyramid walk: skips empty space cell by cell, hits where the ray's depth span "
       "meets a surface, never skips a depth interval",
       {{"max_distance", "length of the reflected ray, view units"},
        {"resolution",
         "0.5 or below: rays of every other pixel of every other row first, and each other pixel's "
         "only where the traced pixels around it disagree (else it takes their hit, or their miss); "
         "above 0.5: every pixel's ray"},
        {"steps", "walk budget per ray, in cells per pyramid level (steps x levels cells at most)"},
        {"thickness",
         "how far behind a surface is solid (a ray there is blocked), view units, where no "
         "back_position gives the real depth"},
        {"blocked",
         "what a blocked ray reports: 'miss' nothing; 'occluder' the uv of what hides its hit, "
         "(u, v, weight, 0): the colour stages show it, the 4th channel says no hit was found"}},
       false, 28, 0, true, &cpu::trace_hiz, "trace_hiz.frag"},
      {March::Exact, "exact",
       "The ground truth: each pixel's mirror ray traced against the scene's triangles (Embree), "
       "reported where the camera sees the hit; runs on the CPU whatever the backend",
       {{"max_distance", "length of the reflected ray, view units: the first hit within it counts"}},
       true, 0, 320, false, &cpu::trace_exact, nullptr},
  };
  return table;
}

const MarchInfo& march_info(March m) {
  for (const MarchInfo& info : march_table())
    if (info.id == m) return info;
  throw Error("glint: march " + std::to_string(static_cast<int>(m)) + " is not in the table");
}

std::string march_names(const char* sep) {
  std::string names;
  for (const MarchInfo& info : march_table()) {
    if (!names.empty()) names += sep;
    names += info.name;
  }
  return names;
}

const MarchInfo& march_info(const std::string& name) {
  for (const MarchInfo& info : march_table())
    if (name == info.name) return info;
  throw InvalidArgument("march", "expected one of " + march_names() + ", got \"" + name + "\"");
}

}  // namespace glint
