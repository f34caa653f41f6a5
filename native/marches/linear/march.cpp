// The book's older linear march ("linear"): fixed view-space steps, stepping
// back and approaching after a hit, exactly as the book's SSR section does,
// in Blender's camera space. Shares the seed's origin checks and texel reads
// (FIX 3 and 4 of docs/conventions.md, march.h). Its GL form is
// trace_linear.frag beside this file; its row of the table of marches is at
// the end.
#include <cmath>

#include "cpu/march.h"
#include "cpu/ray.h"
#include "glint/marches.h"

namespace glint::cpu {
namespace {

void march_linear(const MarchSetup& s, int x, int y, float out[4]) {
  out[0] = out[1] = out[2] = out[3] = 0.0f;
  V3 from, unit_from, normal;
  if (!read_origin(s, x, y, from, unit_from, normal)) return;
  const int steps = s.opt.steps;
  if (steps <= 0) return;

  const V3 reflection = normalize(reflect(unit_from, normal));
  if (!finite(reflection)) return;
  const float thickness = s.opt.thickness;
  float max_distance = s.opt.max_distance;
  float step_size = max_distance / static_cast<float>(steps);
  float count = 1.0f;

  for (int i = 0; i < steps; ++i) {
    const float distance = count * step_size;
    if (distance > max_distance) break;
    const V3 sample = from + reflection * distance;
    float c[4];
    clip_of(s.proj, sample, c);
    // A sample behind the eye (w <= 0) is outside the frustum too: without
    // this test its divided coordinates would flip sign and look inside.
    if (!(c[3] > 0.0f)) break;
    const float ox = c[0] / c[3] * 0.5f + 0.5f;
    const float oy = c[1] / c[3] * 0.5f + 0.5f;
    const float oz = c[2] / c[3];
    if (!(ox >= 0.0f && oy >= 0.0f && oz >= -1.0f && ox <= 1.0f && oy <= 1.0f && oz <= 1.0f)) break;

    float scene_vd;
    const bool seen = fetch_texel(s, ox, oy, scene_vd) >= 0;
    const float sample_vd = view_distance(sample);
    if (seen && sample_vd >= scene_vd && sample_vd <= scene_vd + thickness) {
      const float visibility = clamp01(1.0f - std::fmax(dot(reflection, unit_from * -1.0f), 0.0f));
      // The book writes (u, v, visibility, 1); Glint's buffer contract is
      // (u, v, visibility, visibility) for every march.
      out[0] = ox;
      out[1] = oy;
      out[2] = visibility;
      out[3] = visibility;
      // Step back to the last miss and approach with smaller steps, exactly
      // as the book does (the restart distance is count * new step size).
      count -= 1.0f;
      max_distance = distance;
      const float previous_distance = count * step_size;
      const float steps_left = std::fmax(static_cast<float>(steps - i), 1.0f);
      step_size = (max_distance - previous_distance) / steps_left;
    } else {
      count += 1.0f;
    }
  }
}

Image trace_linear(const TraceInputs& in, const TraceOptions& opt, int threads) {
  return trace_pixels(in, opt, threads, march_linear);
}

}  // namespace
}  // namespace glint::cpu

namespace glint {

MarchInfo glint_march_linear() {
  MarchInfo m;
  m.name = "linear";
  m.description = "The book's older march: fixed view-space steps, stepping back and approaching after a hit";
  m.knobs = {{"max_distance", "length of the reflected ray, view units"},
             {"steps", "view-space steps along the ray (max_distance / steps each)"},
             {"thickness", "how far behind the depth buffer a sample still counts as a hit, view units"}};
  m.scratch_per_pixel = 4;  // one float view distance per texel
  m.cpu = &cpu::trace_linear;
  m.gl_program = "trace_linear.frag";
  return m;
}

}  // namespace glint
