#version 430 core
// The reflection colour blurred by each pixel's GGX cone (docs/look-core.md):
// footprint = 2 * |hit uv - pixel centre| in pixels * cone_tan(alpha), read
// trilinearly from the 2x2 box chain at lod = log2(footprint). Bilinear per
// level is written out with texelFetch, as cpu/look.cpp does, so both
// backends filter alike. Pixels whose footprint is within one texel, that do
// not reflect, or that found nothing keep their own colour.
#include "common.glsl"
#include "fragment.glsl"
#include "look_common.glsl"

uniform sampler2D u_chain;     // level 0 = the reflection colour
uniform sampler2D u_uv;        // (u, v, visibility, visibility)
uniform sampler2D u_specular;
uniform int u_last;            // the chain's last level

layout(location = 0) out vec4 out_color;

vec4 bilinear(int level, vec2 uv) {
  // Level sizes halve with the floor, so level k is size0 >> k (at least 1).
  // Not textureSize(u_chain, level): llvmpipe answers it for one level per
  // SIMD group, and neighbouring pixels may read different levels.
  ivec2 size = max(ivec2(1), textureSize(u_chain, 0) >> level);
  precise float tx = uv.x * float(size.x) - 0.5;
  precise float ty = uv.y * float(size.y) - 0.5;
  float fx = floor(tx), fy = floor(ty);
  precise float ax = tx - fx;
  precise float ay = ty - fy;
  int ix = int(fx), iy = int(fy);
  int x0 = clamp(ix, 0, size.x - 1), x1 = clamp(ix + 1, 0, size.x - 1);
  int y0 = clamp(iy, 0, size.y - 1), y1 = clamp(iy + 1, 0, size.y - 1);
  vec4 a = texelFetch(u_chain, ivec2(x0, y0), level);
  vec4 b = texelFetch(u_chain, ivec2(x1, y0), level);
  vec4 c = texelFetch(u_chain, ivec2(x0, y1), level);
  vec4 d = texelFetch(u_chain, ivec2(x1, y1), level);
  precise vec4 bottom = a * (1.0 - ax) + b * ax;
  precise vec4 top = c * (1.0 - ax) + d * ax;
  precise vec4 r = bottom * (1.0 - ay) + top * ay;
  return r;
}

void main() {
  ivec2 px = pixel_coord();
  vec4 own = texelFetch(u_chain, px, 0);
  out_color = own;
  vec4 s = texelFetch(u_specular, px, 0);
  vec4 t = texelFetch(u_uv, px, 0);
  if (!is_reflective(s) || !(clamp01(t.z) > 0.0)) return;
  if (!finite_f(t.x) || !finite_f(t.y)) return;
  float alpha = look_ggx_alpha(s);
  if (!(alpha > 0.0)) return;
  vec2 size = vec2(textureSize(u_chain, 0));
  vec2 centre = vec2(px) + 0.5;
  precise vec2 delta = t.xy * size - centre;
  precise float len = sqrt(delta.x * delta.x + delta.y * delta.y);
  precise float footprint = 2.0 * len * look_cone_tan(alpha);
  if (!(footprint > 1.0)) return;
  float lod = min(log2(footprint), float(u_last));
  int k0 = int(lod);
  int k1 = min(k0 + 1, u_last);
  precise float f = lod - float(k0);
  vec2 uv = centre / size;
  vec4 c0 = bilinear(k0, uv);
  vec4 c1 = bilinear(k1, uv);
  precise vec4 r = c0 * (1.0 - f) + c1 * f;
  out_color = r;
}
