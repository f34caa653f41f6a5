#version 430 core
// The reflection layer: mix(colour, blurred, roughness) (the colour alone
// when there is no separate blur: a cone blur holds the roughness already),
// times the physical weight (rgb on the colour, a on the alpha) or, without
// one, the seed's specular amount on all four; zero where the pixel does not
// reflect. Roughness = 1 - clamp(shininess, 0, 1) (a non-finite shininess
// counts as 1, smooth), as the CPU backend does.
#include "common.glsl"
#include "fragment.glsl"
#include "look_common.glsl"

uniform sampler2D u_color;     // reflection colour
uniform sampler2D u_blurred;   // its blur
uniform sampler2D u_specular;  // (specular rgb, shininess in [0, 1])
uniform sampler2D u_weight;    // specular_weight
uniform bool u_has_blurred;
uniform bool u_has_weight;

layout(location = 0) out vec4 out_color;

void main() {
  ivec2 px = pixel_coord();
  vec4 s = texelFetch(u_specular, px, 0);
  precise float amount = specular_amount(s);
  if (!(amount > 0.0) || !finite_f(amount)) {
    out_color = vec4(0.0);
    return;
  }
  vec4 c = texelFetch(u_color, px, 0);
  vec4 m = c;
  if (u_has_blurred) {
    float roughness = look_roughness(s);
    vec4 b = texelFetch(u_blurred, px, 0);
    precise vec4 mixed = c * (1.0 - roughness) + b * roughness;
    m = mixed;
  }
  precise vec4 r = u_has_weight ? m * texelFetch(u_weight, px, 0) : m * amount;
  out_color = r;
}
