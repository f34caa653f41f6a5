#version 430 core
// The reflection colour blurred by each pixel's GGX cone (docs/look-core.md):
// footprint = 2 * |hit uv - pixel centre| in pixels * cone_tan(alpha) (no
// wider than a flat mirror's where u_bounded: glint::cone_lod_at()), read
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
// The flat mirror's bound (glint::MirrorScale, cone_lod_at()), where u_bounded.
uniform int u_bounded;
uniform sampler2D u_position;
uniform int u_eye_kind;        // 0 origin, 1 point, 2 direction (glint::EyeKind)
uniform vec3 u_eye;
uniform float u_pixels_per_unit;
uniform vec4 u_w_row;          // the projection's last row: clip w

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

// glint::mirror_footprint() in its operation order: 0 where unknown.
float mirror_footprint(ivec2 px, vec4 t, float tan_c) {
  vec2 size = vec2(textureSize(u_position, 0));
  vec4 p = texelFetch(u_position, px, 0);
  ivec2 h;
  if (!texel_in(t.xy * size, size, h)) return 0.0;
  vec4 q = texelFetch(u_position, h, 0);
  if (!(p.w > 0.0) || !(q.w > 0.0)) return 0.0;
  precise float ex = q.x - p.x;
  precise float ey = q.y - p.y;
  precise float ez = q.z - p.z;
  precise float tl = sqrt(ex * ex + ey * ey + ez * ez);
  vec3 d = incident_toward(u_eye_kind, u_eye, p.xyz);
  precise float dn = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
  if (!(dn > 0.0)) return 0.0;
  precise float sc = tl / dn;
  precise float vx = p.x + sc * d.x;
  precise float vy = p.y + sc * d.y;
  precise float vz = p.z + sc * d.z;
  precise float cw = u_w_row.x * vx + u_w_row.y * vy + u_w_row.z * vz + u_w_row.w;
  precise float f = 2.0 * tl * tan_c * (u_pixels_per_unit / cw);
  return cw > 0.0 && finite_f(f) ? f : 0.0;
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
  float tan_c = look_cone_tan(alpha);
  precise float footprint = 2.0 * len * tan_c;
  if (footprint > 1.0 && u_bounded != 0) {
    float flat_fp = mirror_footprint(px, t, tan_c);
    if (flat_fp > 0.0 && flat_fp < footprint) footprint = flat_fp;
  }
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
