#version 430 core
// The book's older single march ("linear"): fixed view-space steps along the
// reflected ray, and after a hit a step back to the last miss and a finer
// approach. A port of march_linear() in native/src/cpu/march_linear.cpp.
// Output: (u, v, visibility, visibility).
#include "common.glsl"
#include "fragment.glsl"
#include "trace_common.glsl"

layout(location = 0) out vec4 out_uv;

void main() {
  out_uv = vec4(0.0);
  vec3 from, unit_from, normal;
  if (!read_origin(pixel_coord(), from, unit_from, normal)) return;
  int steps = u_steps;
  if (steps <= 0) return;

  vec3 reflection = normalize3(reflect3(unit_from, normal));
  if (!finite_v3(reflection)) return;
  float thickness = u_thickness;
  precise float max_distance = u_max_distance;
  precise float step_size = max_distance / float(steps);
  precise float count = 1.0;
  vec4 position_to;

  for (int i = 0; i < steps; ++i) {
    precise float distance = count * step_size;
    if (distance > max_distance) break;
    precise vec3 sample_view = from + reflection * distance;
    vec4 c = clip_of(sample_view);
    // Behind the eye (w <= 0) is outside the frustum too; without this test
    // the divided coordinates would flip sign and look inside.
    if (!(c.w > 0.0)) break;
    precise float ox = c.x / c.w * 0.5 + 0.5;
    precise float oy = c.y / c.w * 0.5 + 0.5;
    precise float oz = c.z / c.w;
    if (!(ox >= 0.0 && oy >= 0.0 && oz >= -1.0 && ox <= 1.0 && oy <= 1.0 && oz <= 1.0)) break;

    bool seen = fetch_position(vec2(ox, oy), position_to);
    float sample_vd = view_distance(sample_view);
    float scene_vd = view_distance(position_to.xyz);
    precise float far_side = scene_vd + thickness;
    if (seen && sample_vd >= scene_vd && sample_vd <= far_side) {
      precise float visibility = clamp01(1.0 - max(dot3(reflection, unit_from * -1.0), 0.0));
      // The book writes (u, v, visibility, 1); Glint's contract is
      // (u, v, visibility, visibility) for every march.
      out_uv = vec4(ox, oy, visibility, visibility);
      // Step back and approach, exactly as the book does (the restart
      // distance is count * the new step size).
      count -= 1.0;
      max_distance = distance;
      precise float previous_distance = count * step_size;
      precise float steps_left = max(float(steps - i), 1.0);
      step_size = (max_distance - previous_distance) / steps_left;
    } else {
      count += 1.0;
    }
  }
}
