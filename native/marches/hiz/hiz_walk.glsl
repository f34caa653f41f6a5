// The "hiz" march's walk: the Hi-Z pyramid (hiz_base.frag, hiz_reduce.frag)
// walked cell by cell along the reflected ray's screen-space line. A port of
// hiz_walk_scalar() in hiz_walk.cpp (the walk, which explains
// each step) and of march_hiz.cpp (the ray, the texel test);
// same operations in the same order. trace_pixel() returns (u, v, visibility,
// visibility) at a hit (its confidence times the fade at the screen's edge),
// with u_blocked an occluder's (u, v, fade, 0) or, entered by its hidden side,
// (u, v, fade, ENTERED_HIDDEN); else 0. trace_ray() does the same for a ray
// made otherwise (hiz_outline_trace.comp's rays from points off the pixel's
// centre): one walk for both. Apart from trace_hiz.frag's main() so that
// the compute passes can walk the pixels they pick from a list.
// Needs common.glsl, trace_common.glsl and hiz_common.glsl.

uniform sampler2D u_pyramid;  // RG32F, full mip chain: (nearest, farthest + thickness)
uniform int u_levels;
// A texel test's reads, as images: on llvmpipe an imageLoad costs much less
// than a texelFetch of the same texture (the pyramid cannot be read so: each
// lane reads its own level, and an image is one level).
layout(rgba32f, binding = 5) uniform readonly image2D u_position_img;  // the G-buffer's positions
layout(rgba32f, binding = 6) uniform readonly image2D u_planes;  // the plane normals (hiz_base.frag), xyz used
// TraceOptions::blocked: 1 (occluder) reports a blocked ray at the texel that
// blocks it as (u, v, edge fade, 0 or ENTERED_HIDDEN); 0 (miss) reports nothing.
uniform int u_blocked;

// The ray, in the homogeneous form of the CPU's Ray: at screen fraction t
// the view point is A(t) / B(t).
vec2 g_f0, g_d, g_inv, g_nudge;
vec3 g_a0, g_da;
float g_b0, g_db, g_t_end;

float ray_depth(float t) {
  precise float r = -(g_a0.z + t * g_da.z) / (g_b0 + t * g_db);
  return r;
}
// ray_depth(t) = ray_num(t) / ray_b(t), ray_b > 0: the walk compares without dividing.
float ray_num(float t) {
  precise float r = -(g_a0.z + t * g_da.z);
  return r;
}
float ray_b(float t) {
  precise float r = g_b0 + t * g_db;
  return r;
}
float ray_plane(float t, vec3 u, float np) {
  precise float r = u.x * (g_a0.x + t * g_da.x) + u.y * (g_a0.y + t * g_da.y) +
                    u.z * (g_a0.z + t * g_da.z) - np * (g_b0 + t * g_db);
  return r;
}
float ray_exit(ivec4 box) {
  float te = g_t_end;
  if (g_d.x != 0.0) {
    precise float v = (float(g_d.x > 0.0 ? box.z : box.x) - g_f0.x) * g_inv.x;
    te = v < te ? v : te;
  }
  if (g_d.y != 0.0) {
    precise float v = (float(g_d.y > 0.0 ? box.w : box.y) - g_f0.y) * g_inv.y;
    te = v < te ? v : te;
  }
  return te;
}

// `left` in hiz_walk_scalar() (hiz_walk.cpp): bits 0..m for the largest level m
// whose cells the sides of box crossed at te bound (b ^ (b - 1) for a side at
// b: bits 0..ctz(b), all for 0); 0 when te is no side's.
uint left_levels(ivec4 box, float te) {
  uint left = 0u;
  if (g_d.x != 0.0) {
    int b = g_d.x > 0.0 ? box.z : box.x;
    precise float v = (float(b) - g_f0.x) * g_inv.x;
    left |= v == te ? uint(b ^ (b - 1)) : 0u;
  }
  if (g_d.y != 0.0) {
    int b = g_d.y > 0.0 ? box.w : box.y;
    precise float v = (float(b) - g_f0.y) * g_inv.y;
    left |= v == te ? uint(b ^ (b - 1)) : 0u;
  }
  return left;
}

// make_ray_from() in march_hiz.cpp: the ray from view point `from` on the
// reflector, seen along `unit_from`, mirrored about the unit `normal`, into
// the g_ globals.
bool make_ray_from(vec3 from, vec3 unit_from, vec3 normal) {
  vec3 dir = normalize3(reflect3(unit_from, normal));
  if (!finite_v3(dir)) return false;
  float len = clipped_length(from, dir, u_max_distance);
  if (!(len > 0.0)) return false;
  precise vec3 end = from + dir * len;
  vec4 c0 = clip_of(from);
  vec4 c1 = clip_of(end);
  if (!(c0.w > 0.0) || !(c1.w > 0.0)) return false;
  // One reciprocal of w per end serves the projection and A, B alike.
  precise float b0 = 1.0 / c0.w;
  precise float b1 = 1.0 / c1.w;
  precise float f0x = (c0.x * b0 * 0.5 + 0.5) * u_size.x;
  precise float f0y = (c0.y * b0 * 0.5 + 0.5) * u_size.y;
  precise float dx = (c1.x * b1 * 0.5 + 0.5) * u_size.x - f0x;
  precise float dy = (c1.y * b1 * 0.5 + 0.5) * u_size.y - f0y;
  g_f0 = vec2(f0x, f0y);
  g_d = vec2(dx, dy);
  if (!finite_f(f0x) || !finite_f(f0y) || !finite_f(dx) || !finite_f(dy)) return false;
  g_inv = vec2(g_d.x != 0.0 ? 1.0 / g_d.x : 0.0, g_d.y != 0.0 ? 1.0 / g_d.y : 0.0);
  g_nudge = vec2(g_d.x > 0.0 ? CELL_NUDGE : (g_d.x < 0.0 ? -CELL_NUDGE : 0.0),
                 g_d.y > 0.0 ? CELL_NUDGE : (g_d.y < 0.0 ? -CELL_NUDGE : 0.0));
  g_b0 = b0;
  precise float db = b1 - b0;
  g_db = db;
  precise vec3 a0 = from * b0;
  g_a0 = a0;
  precise vec3 da = end * b1 - a0;
  g_da = da;
  g_t_end = 1.0;
  g_t_end = ray_exit(ivec4(0, 0, int(u_size.x), int(u_size.y)));
  return g_t_end > 0.0;
}

// Pixel px's own ray, from its centre.
bool make_ray(ivec2 px) {
  vec3 from, unit_from, normal;
  if (!read_origin(px, from, unit_from, normal)) return false;
  return make_ray_from(from, unit_from, normal);
}

ivec2 cell_at(int level, float t, ivec2 size) {
  precise float px = g_f0.x + t * g_d.x + g_nudge.x;
  precise float py = g_f0.y + t * g_d.y + g_nudge.y;
  // 2^-level from its exponent bits: exactly 1 / 2^level, without a division
  // per step.
  float scale = uintBitsToFloat(uint(127 - level) << 23);
  precise float sx = px * scale;
  precise float sy = py * scale;
  int i = !(sx > 0.0) ? 0 : (sx >= float(size.x) ? size.x - 1 : int(sx));
  int j = !(sy > 0.0) ? 0 : (sy >= float(size.y) ? size.y - 1 : int(sy));
  return ivec2(i, j);
}

ivec4 cell_bounds(int level, ivec2 c, ivec2 size) {
  return ivec4(c.x << level, c.y << level,
               c.x == size.x - 1 ? int(u_size.x) : (c.x + 1) << level,
               c.y == size.y - 1 ? int(u_size.y) : (c.y + 1) << level);
}

const int PASS = 0;
const int HIT = 1;
const int BLOCKED = 2;  // inside the thickness, nearer the front (march_hiz.cpp)
const int ENTERED = 3;  // came in by the hidden side

// unit_plane() in march_hiz.cpp: the unit normal u of usable normal n, u . p
// and the rounding tolerance PLANE_TOLERANCE * |p|.
void unit_plane(vec3 n, vec3 p, out vec3 u, out float np, out float tol) {
  precise float inv = 1.0 / sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
  precise vec3 pu = vec3(n.x * inv, n.y * inv, n.z * inv);
  precise float pnp = pu.x * p.x + pu.y * p.y + pu.z * p.z;
  precise float ptol = PLANE_TOLERANCE * sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
  u = pu;
  np = pnp;
  tol = ptol;
}

// in_front_before() in march_hiz.cpp: the ray, entering texel c at ta, lies in
// front of the plane of the texel it came from (true where nothing says otherwise).
bool in_front_before(ivec2 c, float ta) {
  precise float qx = g_f0.x + ta * g_d.x;
  precise float qy = g_f0.y + ta * g_d.y;
  ivec2 q;  // the cell nudge taken backwards
  if (!texel_at(vec2(qx, qy) - g_nudge, q) || q == c) return true;
  vec4 o = imageLoad(u_position_img, q);
  vec3 n = imageLoad(u_planes, q).xyz;
  if (!texel_seen(o) || !normal_usable(n)) return true;
  vec3 u;
  float np, tol;
  unit_plane(n, o.xyz, u, np, tol);
  return ray_plane(ta, u, np) >= -tol * ray_b(ta);
}

// behind_convex_neighbours() in march_hiz.cpp: false when the ray stays in
// front of a convex neighbour's plane to tb; else t, where it is behind all.
bool behind_convex_neighbours(ivec2 c, vec3 u, float tol, vec3 p, float t0, float tb, out float t) {
  t = t0;
  precise float hx = g_f0.x + t0 * g_d.x;
  precise float hy = g_f0.y + t0 * g_d.y;
  ivec2 nb[2] = ivec2[2](ivec2(hx < float(c.x) + 0.5 ? c.x - 1 : c.x + 1, c.y),
                         ivec2(c.x, hy < float(c.y) + 0.5 ? c.y - 1 : c.y + 1));
  float lim = -texel_thickness(c, -p.z);
  for (int k = 0; k < 2; ++k) {
    ivec2 q = nb[k];
    if (q.x < 0 || q.y < 0 || q.x >= int(u_size.x) || q.y >= int(u_size.y)) continue;
    vec4 o = imageLoad(u_position_img, q);
    vec3 nq = imageLoad(u_planes, q).xyz;
    if (!texel_seen(o) || !normal_usable(nq)) continue;
    precise float g = u.x * (o.x - p.x) + u.y * (o.y - p.y) + u.z * (o.z - p.z);
    if (!(g < -tol) || g < lim) continue;
    vec3 qu;
    float qnp, qtol;
    unit_plane(nq, o.xyz, qu, qnp, qtol);
    precise float gq = qu.x * (p.x - o.x) + qu.y * (p.y - o.y) + qu.z * (p.z - o.z);
    if (!(gq < -qtol)) continue;
    float qa = ray_plane(t, qu, qnp);
    precise float la = -qtol * ray_b(t);
    if (qa < la) continue;
    float qb = ray_plane(tb, qu, qnp);
    precise float lb = -qtol * ray_b(tb);
    if (!(qb < lb)) return false;
    precise float f = qa / (qa - qb);
    f = f < 0.0 ? 0.0 : f;
    f = 1.0 < f ? 1.0 : f;
    precise float tn = t + (tb - t) * f;
    t = tn;
  }
  return true;
}

// off_the_object() in march_hiz.cpp.
bool off_the_object(float pz, float tk, float t) {
  precise float off = ray_depth(t) + pz;
  precise float limit = CROSSING_DEPTH * tk;
  return tk > 0.0 && abs(off) > limit;
}

// n, p: the texel's plane normal (u_planes) and position, for the outline test after a hit.
int texel_hit(ivec2 c, float ta, float tb, out float t_hit, out bool located, out vec3 n, out vec3 p) {
  n = imageLoad(u_planes, c).xyz;
  p = imageLoad(u_position_img, c).xyz;
  t_hit = ta;
  located = false;
  if (!normal_usable(n)) return HIT;
  vec3 u;
  float np, tol;
  unit_plane(n, p, u, np, tol);
  float ga = ray_plane(ta, u, np);
  float gb = ray_plane(tb, u, np);
  precise float lim_a = -tol * ray_b(ta);
  precise float lim_b = -tol * ray_b(tb);
  bool a_behind = ga < lim_a;
  bool b_behind = gb < lim_b;
  if (!a_behind && !b_behind) return PASS;
  if (!a_behind) {
    precise float f = ga / (ga - gb);
    f = f < 0.0 ? 0.0 : f;
    f = 1.0 < f ? 1.0 : f;
    precise float th = ta + (tb - ta) * f;
    t_hit = th;
    located = true;
    float tc;
    if (!behind_convex_neighbours(c, u, tol, p, th, tb, tc)) return PASS;
    t_hit = tc;
    if (off_the_object(p.z, known_thickness(c, -p.z), tc)) return PASS;
    return HIT;
  }
  {
    float tc;
    if (!behind_convex_neighbours(c, u, tol, p, ta, tb, tc)) return PASS;
    if (tc > ta) {
      float gc = ray_plane(tc, u, np);
      precise float lc = -tol * ray_b(tc);
      if (!(gc < lc)) return PASS;
      if (off_the_object(p.z, known_thickness(c, -p.z), tc)) return PASS;
      t_hit = tc;
      located = true;
      return HIT;
    }
  }
  float thick = texel_thickness(c, -p.z);
  if (off_the_object(p.z, thick, ta)) return PASS;
  vec4 L;
  if (!texel_plane(n, p, L)) return HIT;
  precise float sxs = 2.0 / u_size.x;
  precise float sys = 2.0 / u_size.y;
  precise float slack = BEHIND_SLACK * abs(p.z);
  precise float sxa = (g_f0.x + ta * g_d.x) * sxs - 1.0;
  precise float sya = (g_f0.y + ta * g_d.y) * sys - 1.0;
  precise float da = ray_depth(ta) - plane_depth(L, sxa, sya);
  if (da <= slack) {
    located = true;
    return HIT;
  }
  precise float share = HIDDEN_SHARE * thick;
  // The side it came in by, from the texel's own depth, and a late crossing
  // reported as a hit (texel_hit() in march_hiz.cpp says why).
  precise float dc = ray_depth(ta) + p.z;
  if (da <= thick) {
    if (dc > share) return ENTERED;
    if (b_behind && known_thickness(c, -p.z) > 0.0 && in_front_before(c, ta)) {
      located = true;
      return HIT;
    }
    return BLOCKED;
  }
  if (b_behind) {
    precise float sxb = (g_f0.x + tb * g_d.x) * sxs - 1.0;
    precise float syb = (g_f0.y + tb * g_d.y) * sys - 1.0;
    precise float db = ray_depth(tb) - plane_depth(L, sxb, syb);
    if (db <= thick) return ENTERED;
  }
  return PASS;
}

// outline_confidence() and hit_visibility() in march_hiz.cpp.
bool on_screen(ivec2 q) { return q.x >= 0 && q.y >= 0 && q.x < int(u_size.x) && q.y < int(u_size.y); }

// Unseen, or behind the plane (p, n) by more than lim (a negative bound).
bool across_outline(ivec2 q, vec3 p, vec3 n, float lim) {
  vec4 o = imageLoad(u_position_img, q);
  precise float g = n.x * (o.x - p.x) + n.y * (o.y - p.y) + n.z * (o.z - p.z);
  return !(texel_seen(o) && g >= lim);
}

float outline_confidence(ivec2 c, vec3 p, vec3 n, float hx, float hy) {
  float th = texel_thickness(c, -p.z);
  precise float lim = -th * sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
  precise float dx = hx - (float(c.x) + 0.5);
  precise float dy = hy - (float(c.y) + 0.5);
  ivec2 nb[4] = ivec2[4](c - ivec2(1, 0), c + ivec2(1, 0), c - ivec2(0, 1), c + ivec2(0, 1));
  float toward[4] = float[4](-dx, dx, -dy, dy);
  float t = known_thickness(c, -p.z);
  float conf = 1.0;
  for (int k = 0; k < 4; ++k) {
    ivec2 q = nb[k];
    if (!on_screen(q) || !across_outline(q, p, n, lim)) continue;
    float d = min(max(toward[k], 0.0), 0.5);
    ivec2 inner = nb[k ^ 1];
    if (t > 0.0 && on_screen(inner) && !across_outline(inner, p, n, lim)) {
      float t_in = known_thickness(inner, -imageLoad(u_position_img, inner).z);
      precise float fall = t_in - t;
      precise float reach = d * fall;
      if (t_in > t && reach <= t) continue;
    }
    precise float ck = 1.0 - 2.0 * (1.0 - UNCERTAIN) * d;
    conf = min(conf, ck);
  }
  return conf;
}

// screen_edge_fade() in glint/schema.h: the fade looks at the edge the ray of
// pixel `origin` is heading for.
float hit_visibility(ivec2 origin, float u, float v, float confidence) {
  precise float ou = (float(origin.x) + 0.5) / u_size.x;
  precise float ov = (float(origin.y) + 0.5) / u_size.y;
  precise float du = u - ou;
  precise float dv = v - ov;
  precise float mu = du > 0.0 ? 1.0 - u : u;
  precise float mv = dv > 0.0 ? 1.0 - v : v;
  precise float edge;
  if (du == 0.0 && dv == 0.0) {
    edge = min(min(u, 1.0 - u), min(v, 1.0 - v));
  } else {
    precise float su = mu * abs(dv);
    precise float sv = mv * abs(du);
    edge = su <= sv ? mu : mv;
  }
  precise float fade = edge / EDGE_FADE;
  fade = fade < 0.0 ? 0.0 : fade;
  fade = 1.0 < fade ? 1.0 : fade;
  precise float vis = confidence * fade;
  return vis;
}

// hiz_walk_scalar() and queue_texel() (march_hiz.cpp): the ray that
// make_ray_from() prepared, walked to its hit. It starts by leaving texel
// `origin`, whose surface it starts on (walk_from() in march_hiz.cpp).
vec4 trace_ray(ivec2 origin) {
  int top = u_levels - 1;
  int budget = u_steps * u_levels;
  float t = ray_exit(ivec4(origin, origin + 1));
  float nt = ray_num(t);
  float bt = ray_b(t);
  int level = 0;
  // Bit l: the cell of level l the ray is in is known to overlap it
  // (hiz_walk_scalar() says why).
  uint known = 0u;
  int it = 0;
  bool hit = false;
  bool blocked = false;
  bool entered = false;
  ivec2 hit_c;
  float hit_t;
  bool hit_located;
  vec3 hit_n, hit_p;
  // The walk stops at each level-0 texel that may meet the ray and the
  // texel's test runs outside the walk's loop: a SIMD rasterizer such as
  // llvmpipe runs the body of a loop for all lanes whenever any lane needs
  // it, so inside, the test (three fetches and the divisions) would cost
  // every step of the walk instead of the one or two texels a ray tests.
  while (it < budget && t < g_t_end) {
    bool test = false;
    ivec2 c;
    ivec4 box;
    float te, ne, be;
    for (; it < budget && t < g_t_end; ++it) {
      // Level sizes by shift (GL's iterated floor(size / 2) is floor(size / 2^level),
      // at least 1), not textureSize(): llvmpipe was seen to return a stale
      // size for a level that changed inside this loop. The loop has no
      // `continue` for the same reason.
      ivec2 size = max(ivec2(1), ivec2(u_size) >> level);
      c = cell_at(level, t, size);
      box = cell_bounds(level, c, size);
      te = ray_exit(box);
      if (!(te > t)) te = uintBitsToFloat(floatBitsToUint(t) + 1u);  // always move on (t >= 0)
      ne = ray_num(te);
      be = ray_b(te);
      vec2 cell = texelFetch(u_pyramid, c, level).xy;
      precise float lt = cell.x * bt;
      precise float le = cell.x * be;
      precise float ht = cell.y * bt;
      precise float he = cell.y * be;
      bool overlap = (nt >= lt || ne >= le) && (nt <= ht || ne <= he);
      if (overlap && level == 0) {
        test = true;
        break;
      }
      if (overlap) {
        known |= 1u << uint(level);
        --level;  // something in this cell may meet the ray: look closer
      } else {
        t = te;
        nt = ne;
        bt = be;
        known &= ~left_levels(box, te);
        if (level < top && ((known >> uint(level + 1)) & 1u) == 0u) ++level;  // empty so far: a bigger stride
      }
    }
    if (!test) return vec4(0.0);
    float th;
    bool located;
    vec3 n, p;
    int outcome = texel_hit(c, t, te, th, located, n, p);
    if (outcome == BLOCKED || outcome == ENTERED) {
      if (u_blocked == 0) return vec4(0.0);
      blocked = true;  // what hides the hit: its texel's centre (march_hiz.cpp)
      entered = outcome == ENTERED;
      hit_c = c;
      break;
    }
    if (outcome == HIT) {
      hit = true;
      hit_c = c;
      hit_t = th;
      hit_located = located;
      hit_n = n;
      hit_p = p;
      break;
    }
    t = te;
    nt = ne;
    bt = be;
    known &= ~left_levels(box, te);
    if (level < top && ((known >> uint(level + 1)) & 1u) == 0u) ++level;
    ++it;
  }
  // Outside the loops for the same reason: the outline test's five fetches
  // run once per pixel, not once per texel test of any lane.
  if (blocked) {
    vec2 o = (vec2(hit_c) + 0.5) / u_size;
    return vec4(o, hit_visibility(origin, o.x, o.y, 1.0), entered ? ENTERED_HIDDEN : 0.0);
  }
  if (!hit) return vec4(0.0);
  precise float hx = g_f0.x + hit_t * g_d.x;
  precise float hy = g_f0.y + hit_t * g_d.y;
  precise float u = hx / u_size.x;
  precise float v = hy / u_size.y;
  if (!finite_f(u) || !finite_f(v)) return vec4(0.0);
  float conf = hit_located ? outline_confidence(hit_c, hit_p, hit_n, hx, hy) : UNCERTAIN;
  float vis = hit_visibility(origin, u, v, conf);
  return vec4(u, v, vis, vis);
}

// The pixel's own ray walked to its hit.
vec4 trace_pixel(ivec2 origin) {
  if (!make_ray(origin)) return vec4(0.0);
  return trace_ray(origin);
}
