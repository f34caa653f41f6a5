#version 430 core
// The "hiz" march, a pixel per fragment: hiz_walk.glsl's trace_pixel().
#include "common.glsl"
#include "fragment.glsl"
#include "trace_common.glsl"
#include "hiz_common.glsl"
#include "hiz_walk.glsl"

// hiz_reuses_rays() (glint/marches.h): 0 traces each pixel; 1 traces pixel
// (2x, 2y) into a half-size target, which trace_hiz_fill.comp then spreads.
uniform int u_pass;

layout(location = 0) out vec4 out_uv;

void main() {
  ivec2 c = pixel_coord();
  // u_pass 1 draws the half-size target: pixel c traces pixel 2c.
  out_uv = trace_pixel(u_pass == 1 ? c * 2 : c);
}
