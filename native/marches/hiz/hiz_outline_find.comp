#version 430 core
// The hiz march's antialiased outlines, first pass (on_outline() in
// native/src/cpu/outline.cpp, same tests on the same values): every pixel of the traced
// frame, the outline's appended to hiz_outline.glsl's list. A pixel is on a
// reflection's outline when its report is a hit and a neighbour's on the
// same surface a miss or a hidden side entered, or the other way round. The reports are compared
// first, so most pixels never read the G-buffer. A pixel whose reflection
// the cone blur spreads over more than a pixel there is not listed (the
// blur smooths that edge already). Rows of 64 pixels per group, as
// trace_hiz_fill.comp found fastest on llvmpipe.
#include "common.glsl"
#include "trace_common.glsl"
#include "look_common.glsl"
#include "hiz_outline.glsl"

layout(local_size_x = 64) in;

layout(rgba32f, binding = 0) uniform readonly image2D u_out;  // the traced frame
// Images, not the samplers trace_common.glsl declares: on llvmpipe an
// imageLoad costs much less than a texelFetch.
layout(rgba32f, binding = 1) uniform readonly image2D u_position_img;
layout(rgba32f, binding = 2) uniform readonly image2D u_normal_img;
layout(rgba32f, binding = 3) uniform readonly image2D u_specular_img;  // read when u_has_specular

// same_surface() in native/src/cpu/outline.cpp, the test of trace_hiz_fill.comp's
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

// Neighbour q is in the frame and its report is opposite to r.
bool differs(ivec2 q, int r) {
  if (q.x < 0 || q.y < 0 || q.x >= int(u_size.x) || q.y >= int(u_size.y)) return false;
  return opposite_reports(r, report_of(imageLoad(u_out, q)));
}

// cone_lod_at() > 0 (glint/material.h, as cone_blur.frag computes it): the
// cone's footprint at hit report t, seen from pixel c of specular s, spans
// more than a pixel.
bool blurred(ivec2 c, vec4 s, vec4 t) {
  if (!u_has_specular) return false;
  if (!(t.z > 0.0) || !finite_f(t.x) || !finite_f(t.y)) return false;
  float alpha = look_ggx_alpha(s);
  if (!(alpha > 0.0)) return false;
  precise float dx = t.x * u_size.x - (float(c.x) + 0.5);
  precise float dy = t.y * u_size.y - (float(c.y) + 0.5);
  precise float len = sqrt(dx * dx + dy * dy);
  precise float footprint = 2.0 * len * look_cone_tan(alpha);
  return footprint > 1.0;
}

// Neighbour q differs (differs()), lies on the same surface, and the
// reflection of pixel c is sharp at the pair's hit.
bool sharp_pair(ivec2 c, vec4 own, int r, vec4 p, vec3 n, vec4 s, bool d, ivec2 q) {
  if (!d || !same_surface(p, n, q)) return false;
  return !blurred(c, s, r == REPORT_HIT ? own : imageLoad(u_out, q));
}

// The four neighbours written out, not as an array: llvmpipe keeps a
// loop-indexed local array in memory (trace_hiz_fill.comp says more).
bool on_outline(ivec2 c) {
  vec4 own = imageLoad(u_out, c);
  int r = report_of(own);
  if (r == REPORT_OTHER) return false;
  ivec2 q0 = c - ivec2(1, 0), q1 = c + ivec2(1, 0), q2 = c - ivec2(0, 1), q3 = c + ivec2(0, 1);
  bool d0 = differs(q0, r), d1 = differs(q1, r), d2 = differs(q2, r), d3 = differs(q3, r);
  if (!(d0 || d1 || d2 || d3)) return false;
  vec4 s = u_has_specular ? imageLoad(u_specular_img, c) : vec4(0.0);
  if (u_has_specular && !is_reflective(s)) return false;
  vec4 p = imageLoad(u_position_img, c);
  vec3 n = imageLoad(u_normal_img, c).xyz;
  if (!texel_seen(p) || !finite_v3(p.xyz) || !finite_v3(n)) return false;
  return sharp_pair(c, own, r, p, n, s, d0, q0) || sharp_pair(c, own, r, p, n, s, d1, q1) ||
         sharp_pair(c, own, r, p, n, s, d2, q2) || sharp_pair(c, own, r, p, n, s, d3, q3);
}

// The pixel or a 4-neighbour in the frame entered a hidden side.
bool entered_at(ivec2 q) {
  if (q.x < 0 || q.y < 0 || q.x >= int(u_size.x) || q.y >= int(u_size.y)) return false;
  return report_of(imageLoad(u_out, q)) == REPORT_ENTERED;
}

void main() {
  ivec2 c = ivec2(gl_GlobalInvocationID.xy);
  if (c.x >= int(u_size.x) || c.y >= int(u_size.y)) return;
  if (!on_outline(c)) return;
  bool beside = entered_at(c) || entered_at(c - ivec2(1, 0)) || entered_at(c + ivec2(1, 0)) ||
                entered_at(c - ivec2(0, 1)) || entered_at(c + ivec2(0, 1));
  outline_pixel[atomicAdd(count, 1u)] = uint(c.x) | uint(c.y) << 16 | (beside ? BESIDE_HIDDEN_BIT : 0u);
}
