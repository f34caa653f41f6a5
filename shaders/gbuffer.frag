#version 430 core
// The G-buffer pass, fragment side: position (x, y, z, 1), unit normal
// (flipped toward the eye on back faces, screen-space winding as the CPU
// decides it), specular (rgb, shininess_to_alpha). The depth test keeps the
// smallest view distance; see GlState::rasterize for the depth mapping.
#include "common.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;
in vec4 v_tangent;

// Per triangle: index into the material table.
layout(std430, binding = 0) readonly buffer TriangleMaterial { int triangle_material[]; };
// Per material: (specular r, g, b, shininess_to_alpha(shininess)).
layout(std430, binding = 1) readonly buffer MaterialTable { vec4 material_specular[]; };

uniform int u_first_triangle;  // of this draw: gl_PrimitiveID counts from the draw's first
uniform bool u_has_normal_map;
uniform sampler2D u_normal_map;  // tangent space, rgb = n * 0.5 + 0.5; linear, repeat
uniform float u_depth_base;
uniform float u_depth_scale;

layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;
layout(location = 2) out vec4 out_specular;

// Unit vector, or false when v is zero or not finite.
bool try_normalize(inout vec3 v) {
  float len = length3(v);
  if (!(len > 1e-30) || !finite_f(len)) return false;
  v = v * (1.0 / len);
  return true;
}

// The tangent-space normal map on unit normal n (before any flip). Anything
// degenerate (tangent along n, a non-finite texel) leaves n as it is.
vec3 apply_normal_map(vec3 n) {
  vec3 rgb = textureLod(u_normal_map, v_uv, 0.0).rgb;
  if (!finite_v3(rgb)) return n;
  vec3 nt = rgb * 2.0 - vec3(1.0);
  vec3 t = v_tangent.xyz;
  t = t - n * dot3(n, t);
  if (!try_normalize(t)) return n;
  vec3 bt = cross(n, t) * (v_tangent.w < 0.0 ? -1.0 : 1.0);  // Blender: w is the bitangent sign
  vec3 r = t * nt.x + bt * nt.y + n * nt.z;
  return try_normalize(r) ? r : n;
}

void main() {
  // The plane's normal from screen derivatives, for corner normals that
  // interpolate to zero; made to face the way a front face's would.
  // (Non-finite or all-zero corner normals were replaced on the host.)
  vec3 face = cross(dFdx(v_position), dFdy(v_position));
  if (!gl_FrontFacing) face = -face;

  vec3 n = v_normal;
  if (!try_normalize(n)) {
    n = face;
    try_normalize(n);
  }
  if (u_has_normal_map) n = apply_normal_map(n);
  if (!gl_FrontFacing) n = -n;

  out_position = vec4(v_position, 1.0);
  out_normal = vec4(n, 1.0);
  out_specular = material_specular[triangle_material[u_first_triangle + gl_PrimitiveID]];
  gl_FragDepth = (-v_position.z - u_depth_base) * u_depth_scale;
}
