#version 430 core
// The physical weight of a reflection (docs/look-core.md): per channel
// F0 * A + B, with F0 the specular rgb and (A, B) the split-sum table at
// (N.V, GGX alpha), read bilinearly between its nodes with texelFetch as
// glint::env_brdf() does; alpha = the mean of the three. N.V uses the
// camera's real view ray (u_eye_kind / u_eye: glint::camera_eye()).
#include "common.glsl"
#include "fragment.glsl"
#include "look_common.glsl"

uniform sampler2D u_position;
uniform sampler2D u_normal;
uniform sampler2D u_specular;
uniform sampler2D u_env_brdf;  // kEnvBrdfSize^2 nodes, (A, B) in .xy
uniform int u_eye_kind;        // 0 origin, 1 point, 2 direction (glint::EyeKind)
uniform vec3 u_eye;

layout(location = 0) out vec4 out_color;

vec2 env_brdf(float n_dot_v, float alpha) {
  int n = textureSize(u_env_brdf, 0).x;
  float scale = float(n - 1);
  precise float x = sqrt(clamp01(n_dot_v)) * scale;
  precise float y = sqrt(clamp01(alpha)) * scale;
  int x0 = min(int(x), n - 2), y0 = min(int(y), n - 2);
  precise float fx = x - float(x0);
  precise float fy = y - float(y0);
  vec2 v00 = texelFetch(u_env_brdf, ivec2(x0, y0), 0).xy;
  vec2 v10 = texelFetch(u_env_brdf, ivec2(x0 + 1, y0), 0).xy;
  vec2 v01 = texelFetch(u_env_brdf, ivec2(x0, y0 + 1), 0).xy;
  vec2 v11 = texelFetch(u_env_brdf, ivec2(x0 + 1, y0 + 1), 0).xy;
  precise vec2 bottom = v00 * (1.0 - fx) + v10 * fx;
  precise vec2 top = v01 * (1.0 - fx) + v11 * fx;
  precise vec2 r = bottom * (1.0 - fy) + top * fy;
  return r;
}

void main() {
  ivec2 px = pixel_coord();
  out_color = vec4(0.0);
  vec4 p = texelFetch(u_position, px, 0);
  vec4 s = texelFetch(u_specular, px, 0);
  if (!texel_seen(p) || !is_reflective(s)) return;
  vec3 n = texelFetch(u_normal, px, 0).xyz;
  if (!finite_v3(n)) return;
  precise float nn = dot3(n, n);
  if (nn == 0.0) return;
  vec3 d = incident_toward(u_eye_kind, u_eye, p.xyz);
  precise float dd = dot3(d, d);
  if (!(dd > 0.0) || !finite_f(dd)) return;
  precise float inv_n = 1.0 / sqrt(nn);
  precise float inv_d = 1.0 / sqrt(dd);
  precise float dn = dot3(d, n);
  precise float n_dot_v = clamp01(-(dn * inv_n * inv_d));
  vec2 ab = env_brdf(n_dot_v, look_ggx_alpha(s));
  precise vec3 w = s.rgb * ab.x + ab.y;
  precise float mean = (w.r + w.g + w.b) / 3.0;
  out_color = vec4(w, mean);
}
