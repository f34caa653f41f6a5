#version 430 core
// The hiz march's antialiased outlines, first pass (on_outline() in
// march_hiz.cpp, same tests on the same values): every pixel of the traced
// frame, the outline's appended to hiz_outline.glsl's list. A pixel is on a
// reflection's outline when its report is a hit and a neighbour's on the
// same surface a miss, or the other way round. The reports are compared
// first, so most pixels never read the G-buffer. Rows of 64 pixels per
// group, as trace_hiz_fill.comp found fastest on llvmpipe.
#include "common.glsl"
#include "trace_common.glsl"
#include "hiz_outline.glsl"

layout(local_size_x = 64) in;

layout(rgba32f, binding = 0) uniform readonly image2D u_out;  // the traced frame
// Images, not the samplers trace_common.glsl declares: on llvmpipe an
// imageLoad costs much less than a texelFetch.
layout(rgba32f, binding = 1) uniform readonly image2D u_position_img;
layout(rgba32f, binding = 2) uniform readonly image2D u_normal_img;
layout(rgba32f, binding = 3) uniform readonly image2D u_specular_img;  // read when u_has_specular

// same_surface() in march_hiz.cpp, the test of trace_hiz_fill.comp's
// on_surface() for a neighbour q known to be in the frame: q reflects, its
// view distance is within REUSE_DEPTH of p's and its normal within REUSE_COS
// of n.
bool same_surface(vec4 p, vec3 n, ivec2 q) {
  if (u_has_specular && !is_reflective(imageLoad(u_specular_img, q))) return false;
  vec4 pq = imageLoad(u_position_img, q);
  vec3 nq = imageLoad(u_normal_img, q).xyz;
  precise float dz = abs(pq.z - p.z);
  precise float lim = REUSE_DEPTH * abs(p.z);
  if (!texel_seen(pq) || !(dz <= lim)) return false;
  precise float nn = n.x * n.x + n.y * n.y + n.z * n.z;
  precise float d = n.x * nq.x + n.y * nq.y + n.z * nq.z;
  precise float qq = nq.x * nq.x + nq.y * nq.y + nq.z * nq.z;
  precise float dd = d * d;
  precise float need = REUSE_COS * REUSE_COS * nn * qq;
  return d > 0.0 && dd >= need;
}

// Neighbour q is in the frame and reports a hit or a miss other than r.
bool differs(ivec2 q, int r) {
  if (q.x < 0 || q.y < 0 || q.x >= int(u_size.x) || q.y >= int(u_size.y)) return false;
  int rq = report_of(imageLoad(u_out, q));
  return rq != REPORT_OTHER && rq != r;
}

// The four neighbours written out, not as an array: llvmpipe keeps a
// loop-indexed local array in memory (trace_hiz_fill.comp says more).
bool on_outline(ivec2 c) {
  int r = report_of(imageLoad(u_out, c));
  if (r == REPORT_OTHER) return false;
  ivec2 q0 = c - ivec2(1, 0), q1 = c + ivec2(1, 0), q2 = c - ivec2(0, 1), q3 = c + ivec2(0, 1);
  bool d0 = differs(q0, r), d1 = differs(q1, r), d2 = differs(q2, r), d3 = differs(q3, r);
  if (!(d0 || d1 || d2 || d3)) return false;
  if (u_has_specular && !is_reflective(imageLoad(u_specular_img, c))) return false;
  vec4 p = imageLoad(u_position_img, c);
  vec3 n = imageLoad(u_normal_img, c).xyz;
  if (!texel_seen(p) || !finite_v3(p.xyz) || !finite_v3(n)) return false;
  return (d0 && same_surface(p, n, q0)) || (d1 && same_surface(p, n, q1)) || (d2 && same_surface(p, n, q2)) ||
         (d3 && same_surface(p, n, q3));
}

void main() {
  ivec2 c = ivec2(gl_GlobalInvocationID.xy);
  if (c.x >= int(u_size.x) || c.y >= int(u_size.y)) return;
  if (!on_outline(c)) return;
  outline_pixel[atomicAdd(count, 1u)] = uint(c.x) | uint(c.y) << 16;
}
