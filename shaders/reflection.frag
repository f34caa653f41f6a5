#version 430 core
// The reflection layer: mix(colour, blurred, roughness) * specular amount,
// zero where the pixel does not reflect. Roughness = 1 - clamp(shininess, 0, 1)
// (a non-finite shininess counts as 1, smooth), as the CPU backend does.
#include "common.glsl"
#include "fragment.glsl"

uniform sampler2D u_color;     // reflection colour
uniform sampler2D u_blurred;   // its blur
uniform sampler2D u_specular;  // (specular rgb, shininess in [0, 1])

layout(location = 0) out vec4 out_color;

void main() {
  ivec2 px = pixel_coord();
  vec4 s = texelFetch(u_specular, px, 0);
  precise float amount = (s.r + s.g + s.b) / 3.0;
  if (!(amount > 0.0) || !finite_f(amount)) {
    out_color = vec4(0.0);
    return;
  }
  float roughness = 1.0 - clamp01(finite_f(s.a) ? s.a : 1.0);
  vec4 c = texelFetch(u_color, px, 0);
  vec4 b = texelFetch(u_blurred, px, 0);
  precise vec4 r = (c * (1.0 - roughness) + b * roughness) * amount;
  out_color = r;
}
