#version 430 core
// The hiz march's plane normals: each texel's geometric normal from the
// position buffer, the shading normal where that cannot be had. Written once
// per frame for hiz_base.frag and trace_hiz.frag. hiz_plane_normals() in
// native/src/cpu/hiz_planes.cpp, operation for operation.
#include "common.glsl"
#include "fragment.glsl"
#include "trace_common.glsl"

layout(location = 0) out vec4 out_normal;

// Toward the seen neighbour whose depth is closer (the high one on a tie),
// from low to high; false when neither is seen.
bool axis_difference(ivec2 px, vec3 p, ivec2 step, out vec3 e) {
  e = vec3(0.0);
  ivec2 size = ivec2(u_size);
  ivec2 a = px - step;
  ivec2 b = px + step;
  bool lo_seen = false;
  bool hi_seen = false;
  vec4 lo = vec4(0.0);
  vec4 hi = vec4(0.0);
  if (a.x >= 0 && a.y >= 0) {
    lo = texelFetch(u_position, a, 0);
    lo_seen = texel_seen(lo);
  }
  if (b.x < size.x && b.y < size.y) {
    hi = texelFetch(u_position, b, 0);
    hi_seen = texel_seen(hi);
  }
  if (hi_seen && lo_seen) {
    precise float dl = abs(lo.z - p.z);
    precise float dh = abs(hi.z - p.z);
    if (dl < dh) hi_seen = false;
  }
  if (hi_seen) {
    precise vec3 v = vec3(hi.x - p.x, hi.y - p.y, hi.z - p.z);
    e = v;
  } else if (lo_seen) {
    precise vec3 v = vec3(p.x - lo.x, p.y - lo.y, p.z - lo.z);
    e = v;
  } else {
    return false;
  }
  return true;
}

void main() {
  ivec2 px = pixel_coord();
  vec3 s = texelFetch(u_normal, px, 0).xyz;
  out_normal = vec4(s, 0.0);
  vec4 p = texelFetch(u_position, px, 0);
  if (!texel_seen(p) || !finite_v3(s) || (s.x == 0.0 && s.y == 0.0 && s.z == 0.0)) return;
  vec3 ex;
  vec3 ey;
  if (!axis_difference(px, p.xyz, ivec2(1, 0), ex) || !axis_difference(px, p.xyz, ivec2(0, 1), ey)) return;
  precise vec3 c = vec3(ex.y * ey.z - ex.z * ey.y, ex.z * ey.x - ex.x * ey.z, ex.x * ey.y - ex.y * ey.x);
  precise float len2 = c.x * c.x + c.y * c.y + c.z * c.z;
  if (!(len2 > 0.0) || !finite_f(len2)) return;
  precise float inv = 1.0 / sqrt(len2);
  precise float side = s.x * c.x + s.y * c.y + s.z * c.z;
  if (side < 0.0) inv = -inv;
  precise vec3 n = vec3(c.x * inv, c.y * inv, c.z * inv);
  out_normal = vec4(n, 0.0);
}
