#version 430 core
// The reflection over the base image. u_mode 0 ("over"): base * (1 - a) +
// reflection.rgb, the reflection being premultiplied colour; u_mode 1
// ("seed"): the demo's mix, base * (1 - a) + reflection.rgb * a. Alpha is the
// base's.
#include "common.glsl"
#include "fragment.glsl"

uniform sampler2D u_base;
uniform sampler2D u_reflection;
uniform int u_mode;

layout(location = 0) out vec4 out_color;

void main() {
  ivec2 px = pixel_coord();
  vec4 b = texelFetch(u_base, px, 0);
  vec4 r = texelFetch(u_reflection, px, 0);
  float a = clamp01(r.a);
  precise vec3 rgb = u_mode == 0 ? b.rgb * (1.0 - a) + r.rgb : b.rgb * (1.0 - a) + r.rgb * a;
  out_color = vec4(rgb, b.a);
}
