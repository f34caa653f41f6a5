#version 430 core
// The "hiz" march, a pixel per fragment: hiz_walk.glsl's trace_pixel().
#include "common.glsl"
#include "fragment.glsl"
#include "trace_common.glsl"
#include "hiz_common.glsl"
#include "hiz_walk.glsl"

// hiz_reuses_rays() (glint/marches.h): 0 traces each pixel; 1 traces pixel
// (2x, 2y) into a half-size target, which trace_hiz_fill.frag then spreads.
// The depth test runs first so that the pixels the fill pass settled (it
// marks them nearer) never start this program: a SIMD rasterizer then skips
// whole blocks of them instead of running the walk's set-up masked off.
uniform int u_pass;
layout(early_fragment_tests) in;

layout(location = 0) out vec4 out_uv;

void main() {
  ivec2 c = pixel_coord();
  // u_pass 1 draws the half-size target: pixel c traces pixel 2c.
  out_uv = trace_pixel(u_pass == 1 ? c * 2 : c);
}
