#version 430 core
// The reflection over the base image. u_mode 0 ("over"): base * (1 - a) +
// reflection.rgb, the reflection being premultiplied colour; u_mode 1
// ("seed"): the demo's mix, base * (1 - a) + reflection.rgb * a. With a
// specular base ("over" only), the engine's own specular is taken out where
// the trace covered the lobe instead: max(base - spec * coverage.a, 0) +
// reflection.rgb. Alpha is the base's.
#include "common.glsl"
#include "fragment.glsl"

uniform sampler2D u_base;
uniform sampler2D u_reflection;
uniform sampler2D u_specular_base;
uniform sampler2D u_coverage;
uniform int u_mode;
uniform bool u_has_specular_base;

layout(location = 0) out vec4 out_color;

void main() {
  ivec2 px = pixel_coord();
  vec4 b = texelFetch(u_base, px, 0);
  vec4 r = texelFetch(u_reflection, px, 0);
  if (u_has_specular_base) {
    vec3 sb = texelFetch(u_specular_base, px, 0).rgb;
    float cov = clamp01(texelFetch(u_coverage, px, 0).a);
    precise vec3 kept = b.rgb - sb * cov;
    precise vec3 rgb = max(kept, vec3(0.0)) + r.rgb;
    out_color = vec4(rgb, b.a);
    return;
  }
  float a = clamp01(r.a);
  precise vec3 rgb = u_mode == 0 ? b.rgb * (1.0 - a) + r.rgb : b.rgb * (1.0 - a) + r.rgb * a;
  out_color = vec4(rgb, b.a);
}
