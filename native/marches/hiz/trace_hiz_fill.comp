#version 430 core
// The hiz march's reuse of rays (trace_hiz() in march_hiz.cpp, reuse_surface()
// and reuse_reports() in hiz_reuse.cpp, same tests on the same values): after
// trace_hiz.frag traced every other pixel of every other row into u_coarse,
// an invocation per 2x2 quad of the frame. Its traced corner pixel is copied;
// each other pixel takes what its traced neighbours agree on, and where they
// do not, it is appended to the list of hiz_rays.glsl, which
// trace_hiz_list.comp traces. A quad at a time, because its three other
// pixels all look at the same four traced pixels (the quad's corner and the
// three next quads' ones): each is read once, not by up to eight fragments,
// and every lane runs the same kind of pixel, where a fragment pass runs all
// three kinds in each SIMD block. A group is a row of quads: on llvmpipe,
// which runs a group's lanes 8 at a time along x, 64x1 groups made this pass
// 25-30% faster than 8x8 ones (and the list they append, in row order, a
// little faster to walk), with the same result.
#include "common.glsl"
#include "trace_common.glsl"
#include "hiz_rays.glsl"

layout(local_size_x = 64) in;

layout(rgba32f, binding = 0) uniform writeonly image2D u_out;
// Its inputs as images: on llvmpipe an imageLoad costs much less than a
// texelFetch of the same texture (this pass took about 40% less time).
layout(rgba32f, binding = 1) uniform readonly image2D u_position_img;
layout(rgba32f, binding = 2) uniform readonly image2D u_normal_img;
layout(rgba32f, binding = 3) uniform readonly image2D u_specular_img;  // read when u_has_specular
layout(rgba32f, binding = 4) uniform readonly image2D u_coarse;  // (w + 1) / 2 x (h + 1) / 2: pixel (2x, 2y)'s result

// REUSE_COS, REUSE_DEPTH, REUSE_PIXELS, REUSE_SPAN_PIXELS,
// REUSE_SPAN_VISIBILITY: schema.glsl (glint::hiz::kReuse*).

// A traced pixel as its neighbours see it.
struct Traced {
  bool inside;      // in the frame
  bool reflective;  // is_reflective(), or no specular given
  vec4 p;           // position
  vec3 n;           // normal
  vec4 r;           // its result (u_coarse)
};

Traced traced(ivec2 q) {
  Traced t;
  t.inside = q.x < int(u_size.x) && q.y < int(u_size.y);
  t.reflective = !u_has_specular || is_reflective(imageLoad(u_specular_img, q));
  t.p = imageLoad(u_position_img, q);
  t.n = imageLoad(u_normal_img, q).xyz;
  t.r = imageLoad(u_coarse, q >> 1);
  return t;
}

// The per-neighbour half of reuse_surface(): q lies on the pixel's smooth
// surface (p, n, nn = |n|^2).
// normals_agree() in cpu/outline.h: normals n (|n|^2 = nn) and m lie within
// REUSE_COS of each other.
bool normals_agree(vec3 n, float nn, vec3 m) {
  precise float d = n.x * m.x + n.y * m.y + n.z * m.z;
  precise float mm = m.x * m.x + m.y * m.y + m.z * m.z;
  precise float dd = d * d;
  precise float need = REUSE_COS * REUSE_COS * nn * mm;
  return d > 0.0 && dd >= need;
}

bool on_surface(vec4 p, vec3 n, float nn, Traced q) {
  if (!q.inside) return false;
  if (!q.reflective) return false;
  vec4 pq = q.p;
  vec3 nq = q.n;
  precise float dz = abs(pq.z - p.z);
  precise float lim = REUSE_DEPTH * abs(p.z);
  if (!texel_seen(pq) || !(dz <= lim)) return false;
  return normals_agree(n, nn, nq);
}

// A hit (1), an occluder found late (0) or a hidden side entered (-1).
int report_kind(vec4 r) { return r.w > 0.0 ? 1 : (r.w == 0.0 ? 0 : -1); }

// Two neighbours' hits within `span` pixels of each other; `wide` is set
// when they are further apart than REUSE_PIXELS.
bool close_hits(vec4 ha, vec4 hb, float span, inout bool wide) {
  precise float du = (ha.x - hb.x) * u_size.x;
  precise float dv = (ha.y - hb.y) * u_size.y;
  precise float dist2 = du * du + dv * dv;
  if (!(dist2 <= REUSE_PIXELS * REUSE_PIXELS)) wide = true;
  return dist2 <= span * span;
}

// on_plane_of() in march_hiz.cpp: the texel under uv b lies on the plane of
// the texel under uv a. Both uvs are hits' or their mean, inside the frame.
bool on_plane_of(vec2 a, vec2 b) {
  ivec2 qa, qb;
  if (!texel_at(a * u_size, qa) || !texel_at(b * u_size, qb)) return false;
  vec4 pa = imageLoad(u_position_img, qa);
  vec4 pb = imageLoad(u_position_img, qb);
  if (!texel_seen(pa) || !texel_seen(pb)) return false;
  vec3 na = imageLoad(u_normal_img, qa).xyz;
  vec3 nb = imageLoad(u_normal_img, qb).xyz;
  precise float nn = na.x * na.x + na.y * na.y + na.z * na.z;
  if (!normals_agree(na, nn, nb)) return false;
  precise float g = na.x * (pb.x - pa.x) + na.y * (pb.y - pa.y) + na.z * (pb.z - pa.z);
  precise float lim = REUSE_DEPTH * abs(pa.z) * sqrt(nn);
  return abs(g) <= lim;
}

// reuse_surface() and reuse_reports() for the pixel at c, its k = 2 or 4
// traced neighbours q0..q3 (q2, q3 unused when k = 2), written out without
// arrays: a SIMD compiler such as llvmpipe's keeps a loop-indexed local array
// in memory, one gather per lane and access, which cost this pass most of
// its time.
bool reuse_neighbours(ivec2 c, Traced q0, Traced q1, Traced q2, Traced q3, int k, out vec4 o) {
  o = vec4(0.0);
  vec4 p = imageLoad(u_position_img, c);
  vec3 n = imageLoad(u_normal_img, c).xyz;
  // Only where the pixel's own ray exists (read_origin() would take it).
  if (!texel_seen(p) || !finite_v3(p.xyz) || !finite_v3(n)) return false;
  precise float nn = n.x * n.x + n.y * n.y + n.z * n.z;
  if (!on_surface(p, n, nn, q0) || !on_surface(p, n, nn, q1)) return false;
  if (k == 4 && (!on_surface(p, n, nn, q2) || !on_surface(p, n, nn, q3))) return false;
  int hits = (q0.r.z > 0.0 ? 1 : 0) + (q1.r.z > 0.0 ? 1 : 0);
  if (k == 4) hits += (q2.r.z > 0.0 ? 1 : 0) + (q3.r.z > 0.0 ? 1 : 0);
  if (hits == 0) return true;
  if (hits < k) return false;
  // One kind of report (reuse_reports() in hiz_reuse.cpp says why).
  int kind = report_kind(q0.r);
  if (report_kind(q1.r) != kind) return false;
  if (k == 4 && (report_kind(q2.r) != kind || report_kind(q3.r) != kind)) return false;
  // Real hits further apart, up to REUSE_SPAN_PIXELS, when on one plane (below).
  float span = kind == 1 ? REUSE_SPAN_PIXELS : REUSE_PIXELS;
  bool wide = false;
  if (!close_hits(q0.r, q1.r, span, wide)) return false;
  if (k == 4 && (!close_hits(q0.r, q2.r, span, wide) || !close_hits(q0.r, q3.r, span, wide) ||
                 !close_hits(q1.r, q2.r, span, wide) || !close_hits(q1.r, q3.r, span, wide) ||
                 !close_hits(q2.r, q3.r, span, wide)))
    return false;
  // The sums in the CPU's order, from 0.
  precise float su = 0.0;
  precise float sv = 0.0;
  su += q0.r.x;
  sv += q0.r.y;
  su += q1.r.x;
  sv += q1.r.y;
  float vis = min(min(1.0, q0.r.z), q1.r.z);
  float found = min(min(1.0, q0.r.w), q1.r.w);  // 0 where an occluder stands in
  if (k == 4) {
    su += q2.r.x;
    sv += q2.r.y;
    su += q3.r.x;
    sv += q3.r.y;
    vis = min(min(vis, q2.r.z), q3.r.z);
    found = min(min(found, q2.r.w), q3.r.w);
  }
  precise float inv_k = 1.0 / float(k);
  precise float ou = su * inv_k;
  precise float ov = sv * inv_k;
  if (wide) {
    float vis_max = max(q0.r.z, q1.r.z);
    if (k == 4) vis_max = max(vis_max, max(q2.r.z, q3.r.z));
    precise float vis_step = vis_max - vis;
    if (!(vis_step <= REUSE_SPAN_VISIBILITY)) return false;
    if (!on_plane_of(q0.r.xy, q1.r.xy) || !on_plane_of(q0.r.xy, vec2(ou, ov))) return false;
    if (k == 4 && (!on_plane_of(q0.r.xy, q2.r.xy) || !on_plane_of(q0.r.xy, q3.r.xy))) return false;
    // On one plane the mean visibility, summed in the CPU's order.
    precise float vs = 0.0;
    vs += q0.r.z;
    vs += q1.r.z;
    if (k == 4) {
      vs += q2.r.z;
      vs += q3.r.z;
    }
    precise float mv = vs * inv_k;
    vis = mv;
    found = mv;
  }
  o = vec4(ou, ov, vis, found);
  return true;
}

// Pixel c of the quad: its result written, or c listed (true).
bool settle(ivec2 c, Traced q0, Traced q1, Traced q2, Traced q3, int k) {
  vec4 o = vec4(0.0);
  // Not reflective: the trace writes 0 there, as here.
  if (u_has_specular && !is_reflective(imageLoad(u_specular_img, c))) {
    imageStore(u_out, c, o);
    return false;
  }
  if (reuse_neighbours(c, q0, q1, q2, q3, k, o)) {
    imageStore(u_out, c, o);
    return false;
  }
  return true;
}

void main() {
  ivec2 a = ivec2(gl_GlobalInvocationID.xy) * 2;  // the quad's traced pixel
  ivec2 size = ivec2(u_size);
  if (a.x >= size.x || a.y >= size.y) return;
  Traced ta = traced(a);
  imageStore(u_out, a, ta.r);
  bool right = a.x + 1 < size.x, up = a.y + 1 < size.y;
  // The traced pixels right of, above and diagonal to the quad; outside the
  // frame they are read but never used (reuse_neighbours() stops at them).
  Traced tb = traced(a + ivec2(2, 0));
  Traced tc = traced(a + ivec2(0, 2));
  Traced td = traced(a + ivec2(2, 2));
  // Between two traced pixels of its row, between two of its column, at the
  // centre of four.
  bool row = right && settle(a + ivec2(1, 0), ta, tb, ta, tb, 2);
  bool column = up && settle(a + ivec2(0, 1), ta, tc, ta, tc, 2);
  bool centre = right && up && settle(a + ivec2(1, 1), ta, tb, tc, td, 4);
  uint n = uint(row) + uint(column) + uint(centre);
  if (n == 0u) return;
  uint i = atomicAdd(count, n);
  if (row) pixel[i++] = uint(a.x + 1) | uint(a.y) << 16;
  if (column) pixel[i++] = uint(a.x) | uint(a.y + 1) << 16;
  if (centre) pixel[i] = uint(a.x + 1) | uint(a.y + 1) << 16;
}
