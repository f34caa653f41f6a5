#version 430 core
// The hiz march's antialiased outlines, last pass (resolve_outline() in
// native/src/cpu/outline.cpp, same operations in the same order): an invocation per
// listed pixel of the batch (hiz_outline.glsl), its report in the frame
// replaced by the box filter of its centre and its u_per_pixel samples, a
// hidden side entered counting as no hit. Only where every hit lies within
// REUSE_PIXELS of the first and nothing but hits and misses, or hits and
// hidden sides, was reported; elsewhere the centre's report stays.
#include "common.glsl"
#include "hiz_outline.glsl"

layout(local_size_x = 64) in;  // OUTLINE_GROUP

layout(rgba32f, binding = 0) uniform image2D u_out;  // the traced frame, each listed pixel read and written once

uniform vec2 u_size;  // float(width), float(height)

// One report into the sums: false where it stops the filter (a miss and a
// hidden side both seen: the share the hits leave has no one owner).
bool add(vec4 s, vec4 ref, inout float su, inout float sv, inout float sw, inout bool miss, inout bool entered) {
  int r = report_of(s);
  miss = miss || r == REPORT_MISS;
  entered = entered || r == REPORT_ENTERED;
  if (r != REPORT_HIT) return (r == REPORT_MISS || r == REPORT_ENTERED) && !(miss && entered);
  precise float du = (s.x - ref.x) * u_size.x;
  precise float dv = (s.y - ref.y) * u_size.y;
  precise float dist2 = du * du + dv * dv;
  if (!(dist2 <= REUSE_PIXELS * REUSE_PIXELS)) return false;
  precise float nu = su + s.w * s.x;
  precise float nv = sv + s.w * s.y;
  precise float nw = sw + s.w;
  su = nu;
  sv = nv;
  sw = nw;
  return true;
}

void main() {
  uint i = invocation_index();
  if (i >= batch_pixels()) return;
  uint listed = outline_pixel[uint(u_first) + i];
  ivec2 c = unpack_pixel(listed);
  uint base = i * uint(u_per_pixel);
  vec4 centre = imageLoad(u_out, c);
  // The first hit, the centre's before the samples'.
  vec4 ref = centre;
  bool found = centre.w > 0.0;
  for (int j = 0; j < u_per_pixel && !found; ++j) {
    vec4 s = sample_report[base + uint(j)];
    if (s.w > 0.0) {
      ref = s;
      found = true;
    }
  }
  if (!found) return;
  float su = 0.0, sv = 0.0, sw = 0.0;
  bool miss = false, entered = false;
  if (!add(centre, ref, su, sv, sw, miss, entered)) return;
  for (int j = 0; j < u_per_pixel; ++j)
    if (!add(sample_report[base + uint(j)], ref, su, sv, sw, miss, entered)) return;
  precise float vis = sw / float(u_per_pixel + 1);
  precise float ou = su / sw;
  precise float ov = sv / sw;
  // Beside a hidden side, one hit's uv (resolve_outline() says why).
  bool one = (listed & BESIDE_HIDDEN_BIT) != 0u || entered;
  imageStore(u_out, c, vec4(one ? ref.x : ou, one ? ref.y : ov, vis, vis));
}
