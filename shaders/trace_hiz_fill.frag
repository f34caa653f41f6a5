#version 430 core
// The hiz march's reuse of rays (trace_hiz() and reuse_neighbours() in
// native/src/cpu/march_hiz.cpp, same operations in the same order): every
// pixel of the frame, after trace_hiz.frag traced every other pixel of every
// other row into u_coarse. A traced pixel is copied; another takes what its
// traced neighbours agree on. Where they do not, the pixel is appended to the
// list of hiz_rays.glsl, which trace_hiz_list.comp traces, and left unwritten.
#include "common.glsl"
#include "fragment.glsl"
#include "trace_common.glsl"
#include "hiz_rays.glsl"

uniform sampler2D u_coarse;  // RGBA32F, (w + 1) / 2 x (h + 1) / 2: pixel (2x, 2y)'s result

layout(location = 0) out vec4 out_uv;

// kReuseCos, kReuseDepth, kReusePixels in march_hiz.cpp.
const float REUSE_COS = 0.98;
const float REUSE_DEPTH = 0.02;
const float REUSE_PIXELS = 3.0;

vec4 coarse(ivec2 q) { return texelFetch(u_coarse, q >> 1, 0); }

bool reuse_neighbours(ivec2 c, ivec2 q[4], int k, out vec4 o) {
  o = vec4(0.0);
  vec4 p = texelFetch(u_position, c, 0);
  vec3 n = texelFetch(u_normal, c, 0).xyz;
  // Only where the pixel's own ray exists (read_origin() would take it).
  if (!texel_seen(p) || !finite_v3(p.xyz) || !finite_v3(n)) return false;
  precise float nn = n.x * n.x + n.y * n.y + n.z * n.z;
  int hits = 0;
  for (int e = 0; e < k; ++e) {
    ivec2 qe = q[e];
    if (qe.x < 0 || qe.y < 0 || qe.x >= int(u_size.x) || qe.y >= int(u_size.y)) return false;
    if (u_has_specular && !is_reflective(texelFetch(u_specular, qe, 0))) return false;
    vec4 pq = texelFetch(u_position, qe, 0);
    vec3 nq = texelFetch(u_normal, qe, 0).xyz;
    precise float dz = abs(pq.z - p.z);
    precise float lim = REUSE_DEPTH * abs(p.z);
    if (!texel_seen(pq) || !(dz <= lim)) return false;
    precise float d = n.x * nq.x + n.y * nq.y + n.z * nq.z;
    precise float qq = nq.x * nq.x + nq.y * nq.y + nq.z * nq.z;
    precise float dd = d * d;
    precise float need = REUSE_COS * REUSE_COS * nn * qq;
    if (!(d > 0.0) || !(dd >= need)) return false;
    if (coarse(qe).z > 0.0) ++hits;
  }
  if (hits == 0) return true;
  if (hits < k) return false;
  precise float su = 0.0;
  precise float sv = 0.0;
  float vis = 1.0;
  for (int a = 0; a < k; ++a) {
    vec4 ha = coarse(q[a]);
    for (int b = a + 1; b < k; ++b) {
      vec4 hb = coarse(q[b]);
      precise float du = (ha.x - hb.x) * u_size.x;
      precise float dv = (ha.y - hb.y) * u_size.y;
      precise float dist2 = du * du + dv * dv;
      if (!(dist2 <= REUSE_PIXELS * REUSE_PIXELS)) return false;
    }
    su += ha.x;
    sv += ha.y;
    vis = min(vis, ha.z);
  }
  precise float inv_k = 1.0 / float(k);
  precise float ou = su * inv_k;
  precise float ov = sv * inv_k;
  o = vec4(ou, ov, vis, vis);
  return true;
}

void main() {
  ivec2 c = pixel_coord();
  out_uv = vec4(0.0);
  if ((c.x & 1) == 0 && (c.y & 1) == 0) {
    out_uv = coarse(c);
    return;
  }
  // Not reflective: the trace writes 0 there, as here.
  if (u_has_specular && !is_reflective(texelFetch(u_specular, c, 0))) return;
  ivec2 q[4];
  int k = 2;
  if ((c.y & 1) == 0) {  // between two traced pixels of its row
    q[0] = c - ivec2(1, 0);
    q[1] = c + ivec2(1, 0);
  } else if ((c.x & 1) == 0) {  // between two of its column
    q[0] = c - ivec2(0, 1);
    q[1] = c + ivec2(0, 1);
  } else {  // at the centre of four
    q[0] = c + ivec2(-1, -1);
    q[1] = c + ivec2(1, -1);
    q[2] = c + ivec2(-1, 1);
    q[3] = c + ivec2(1, 1);
    k = 4;
  }
  vec4 o;
  if (reuse_neighbours(c, q, k, o)) {
    out_uv = o;
    return;
  }
  // Left to trace_hiz_list.comp, which writes the pixel: discarded here so
  // that no framebuffer write races its image store.
  pixel[atomicAdd(count, 1u)] = uint(c.x) | uint(c.y) << 16;
  discard;
}
