#version 430 core
// The colour the reflected uv points at, premultiplied by visibility:
// (colour * a, a) with a = clamp(visibility, 0, 1). The colour texture is
// sampled GL_LINEAR with GL_CLAMP_TO_EDGE, as the CPU's sample_bilinear()
// does by hand; its non-finite values were zeroed on upload, as the CPU
// reads them.
#include "common.glsl"
#include "fragment.glsl"

uniform sampler2D u_uv;     // (u, v, visibility, visibility), texelFetch
uniform sampler2D u_color;  // base colour, linear filtering, clamp to edge

layout(location = 0) out vec4 out_color;

void main() {
  vec4 t = texelFetch(u_uv, pixel_coord(), 0);
  float alpha = clamp01(t.z);
  if (!(alpha > 0.0) || !finite_v4(t)) {
    out_color = vec4(0.0);
    return;
  }
  vec4 c = textureLod(u_color, t.xy, 0.0);
  precise vec3 rgb = c.rgb * alpha;
  out_color = vec4(rgb, alpha);
}
