// The "hiz" march's row of the table of marches. Its code is beside this
// file: on the CPU march_hiz.cpp (the trace), hiz_planes.cpp and
// hiz_walk*.cpp; on GL gl_passes.cpp, which runs the shaders hiz_*.glsl,
// hiz_*.{frag,comp} and trace_hiz*.{frag,comp}.
#include "glint/marches.h"
#include "hiz.h"

namespace glint {

MarchInfo glint_march_hiz() {
  MarchInfo m;
  m.name = "hiz";
  m.description =
      "Min/max depth pyramid walk: skips empty space cell by cell, hits where the ray's depth span "
      "meets a surface, never skips a depth interval";
  m.knobs = {{"max_distance", "length of the reflected ray, view units"},
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
              "(u, v, weight, 0): the colour stages show it, the 4th channel says no hit was found"},
             {"antialias",
              "extra rays from inside a pixel on a reflection's outline (a hit beside a miss), whose share "
              "of hits becomes its visibility: 0 one ray per pixel, up to 4 (a rotated grid)"}};
  // The pyramid: 2 floats per cell, 4/3 cells per texel, rounded up; the
  // plane normals 3 floats per texel. Antialiased outlines: a report byte
  // per pixel (CPU), or the outline list's 4 bytes and a batch of samples,
  // a quarter of the pixels at 16 bytes (GL): 9 more.
  m.scratch_per_pixel = 37;
  m.uses_back_position = true;
  m.cpu = &cpu::trace_hiz;
  m.gl_program = "trace_hiz.frag";
#ifdef GLINT_HAVE_GL
  m.gl_trace = &gl::trace_hiz;  // the pyramid first, and the reuse of rays
#endif
  return m;
}

}  // namespace glint
