// The hiz march's plane normals: each texel's geometric normal from the
// position buffer, the shading normal where that cannot be had. hiz_base.frag
// writes them once per frame, beside the pyramid's base, for hiz_walk.glsl.
// hiz_plane_normals_row() in hiz_planes.cpp, operation for
// operation. Needs common.glsl and trace_common.glsl.

// The G-buffer's position and normal textures, read as images: the plane
// normal reads nine positions per texel, and on llvmpipe an imageLoad costs
// much less than a texelFetch (hiz_base.frag took about 1/3 less time), for
// the same values.
layout(rgba32f, binding = 0) uniform readonly image2D u_position_img;
layout(rgba32f, binding = 1) uniform readonly image2D u_normal_img;

// The seen texel `k` steps along `step`, or false.
bool neighbour(ivec2 px, ivec2 step, int k, out vec4 q) {
  ivec2 c = px + k * step;
  ivec2 size = ivec2(u_size);
  q = vec4(0.0);
  if (c.x < 0 || c.y < 0 || c.x >= size.x || c.y >= size.y) return false;
  q = imageLoad(u_position_img, c);
  return texel_seen(q);
}

// How far the depth one side predicts for the texel misses its own (miss()
// in hiz_planes.cpp).
float miss(vec3 p, vec4 a1, bool has_a2, vec4 a2) {
  precise float r;
  if (has_a2) {
    precise float e = 2.0 * a1.z - a2.z;
    r = abs(e - p.z);
  } else {
    r = abs(a1.z - p.z);
  }
  return r;
}

// Toward the seen neighbour whose side predicts the texel's depth better
// (the high one on a tie), from low to high; false when neither is seen.
bool axis_difference(ivec2 px, vec3 p, ivec2 step, out vec3 e) {
  e = vec3(0.0);
  vec4 lo;
  vec4 hi;
  vec4 lo2;
  vec4 hi2;
  bool lo_seen = neighbour(px, step, -1, lo);
  bool hi_seen = neighbour(px, step, 1, hi);
  if (hi_seen && lo_seen) {
    bool lo2_seen = neighbour(px, step, -2, lo2);
    bool hi2_seen = neighbour(px, step, 2, hi2);
    if (miss(p, lo, lo2_seen, lo2) < miss(p, hi, hi2_seen, hi2)) hi_seen = false;
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

vec3 plane_normal(ivec2 px) {
  vec3 s = imageLoad(u_normal_img, px).xyz;
  vec4 p = imageLoad(u_position_img, px);
  if (!texel_seen(p) || !finite_v3(s) || (s.x == 0.0 && s.y == 0.0 && s.z == 0.0)) return s;
  vec3 ex;
  vec3 ey;
  if (!axis_difference(px, p.xyz, ivec2(1, 0), ex) || !axis_difference(px, p.xyz, ivec2(0, 1), ey)) return s;
  precise vec3 c = vec3(ex.y * ey.z - ex.z * ey.y, ex.z * ey.x - ex.x * ey.z, ex.x * ey.y - ex.y * ey.x);
  precise float len2 = c.x * c.x + c.y * c.y + c.z * c.z;
  if (!(len2 > 0.0) || !finite_f(len2)) return s;
  precise float inv = 1.0 / sqrt(len2);
  precise float side = s.x * c.x + s.y * c.y + s.z * c.z;
  if (side < 0.0) inv = -inv;
  precise vec3 n = vec3(c.x * inv, c.y * inv, c.z * inv);
  return n;
}
