// The "hiz" march: a min/max depth pyramid walked cell by cell along the
// reflected ray's screen-space line (docs/hiz.md has the derivation).
//
// Why not the seed's point samples: a sample tests one point of the ray
// against one texel, so a grazing ray that crosses more than `thickness` of
// depth between two samples passes through surfaces unseen, and a thicker
// `thickness` reports rays that pass behind objects. Here every stretch of
// the ray is tested as an interval: across a cell the ray covers a depth span
// [depth(t_in), depth(t_out)] (depth is monotonic along a line in screen
// space), and the cell is entered only if that span meets the cell's
// [nearest surface, farthest surface + thickness]. Empty space is skipped a
// whole cell at a time and no interval of depth is ever jumped over. The walk
// itself is hiz_walk.cpp's (sixteen rays at once on AVX2); this file makes each
// ray, builds the pyramid and tests the texels the walk stops at.
//
// At a texel the surface is the texel's tangent plane (its position and
// geometric normal, hiz_plane_normals_row()), not a flat depth: its depth range covers the texel's footprint, so
// a wall seen at a grazing angle is continuous instead of a staircase, and a
// hit is where the ray crosses that plane, to a fraction of a texel. A ray
// that stays in front of the plane is no hit, which is what keeps a floor's
// own reflection rays from hitting the floor next to where they started.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "cpu/outline.h"
#include "cpu/ray.h"
#include "glint/errors.h"
#include "glint/marches.h"
#include "glint/schema.h"
#include "glint/stages.h"
#include "hiz.h"
#include "hiz_base.h"
#include "parallel.h"

namespace glint::cpu {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
// The method's constants, and why each has its value: glint/schema.h.
constexpr float kCellNudge = hiz::kCellNudge;
constexpr float kPlaneTolerance = hiz::kPlaneTolerance;
constexpr float kBehindSlack = hiz::kBehindSlack;
constexpr float kUncertain = hiz::kUncertain;
constexpr float kEnteredHidden = hiz::kEnteredHidden;
constexpr float kHiddenShare = hiz::kHiddenShare;
constexpr float kCrossingDepth = hiz::kCrossingDepth;
constexpr float kFootprintSpread = hiz::kFootprintSpread;
// Levels of a pyramid over int-sized images: at most 31 halvings to 1x1.
constexpr int kMaxLevels = 32;

// The tangent plane's view distance at screen point (sx, sy) in NDC: the
// plane is L . (sx, sy, sz, 1) = 0 in NDC (L = n^T H_xyz - k H_w), which
// gives sz, and the view point there is H (sx, sy, sz, 1).
inline float plane_depth(const float* H, const float L[4], float sx, float sy) {
  const float sz = -(L[0] * sx + L[1] * sy + L[3]) / L[2];
  const float num = H[8] * sx + H[9] * sy + H[10] * sz + H[11];
  const float den = H[12] * sx + H[13] * sy + H[14] * sz + H[15];
  return -(num / den);
}

inline bool normal_usable(const float* n) {
  return finite(V3{n[0], n[1], n[2]}) && (n[0] != 0.0f || n[1] != 0.0f || n[2] != 0.0f);
}

// A texel's plane as the plane test uses it: the unit normal u, u . p for
// its position p, and the rounding tolerance kPlaneTolerance * |p|. `n` must
// be usable (normal_usable()).
struct UnitPlane {
  float u[3], np, tol;
};
inline UnitPlane unit_plane(const float* n, const float* p) {
  const float inv = 1.0f / std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  UnitPlane pl{{n[0] * inv, n[1] * inv, n[2] * inv}, 0.0f, 0.0f};
  pl.np = pl.u[0] * p[0] + pl.u[1] * p[1] + pl.u[2] * p[2];
  pl.tol = kPlaneTolerance * std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  return pl;
}

// The plane row L of texel (x, y) in NDC (see plane_depth); false when the
// texel has no usable normal or the plane is seen exactly edge-on.
inline bool texel_plane(const Image& position, const HizPlanes& normal, const HizCamera& cam, int x, int y,
                        float L[4]) {
  const float* n = normal.px(x, y);
  if (!normal_usable(n)) return false;
  const float* p = position.px(x, y);
  const float* H = cam.inv;
  const float k = n[0] * p[0] + n[1] * p[1] + n[2] * p[2];
  for (int c = 0; c < 4; ++c) L[c] = n[0] * H[c] + n[1] * H[4 + c] + n[2] * H[8 + c] - k * H[12 + c];
  return L[2] != 0.0f;
}

// Base level: each seen texel's [nearest, farthest + thickness] view distance
// over its footprint.
void base_range(const Image& position, const HizPlanes& normal, const Image* back, const HizCamera& cam,
                float thickness, bool seen, int x, int y, float out[2]) {
  const float* p = position.px(x, y);
  if (!seen) {
    out[0] = kInf;
    out[1] = -kInf;
    return;
  }
  const float d = -p[2];
  const float t = texel_thickness(position, back, thickness, x, y);
  float lo = d, hi = d;
  float L[4];
  if (texel_plane(position, normal, cam, x, y, L)) {
    const float spread = kFootprintSpread * std::fabs(d) + t;
    const float w = static_cast<float>(position.width), h = static_cast<float>(position.height);
    // On the plane, sz and so the view point's z and w are affine in (sx, sy):
    // one reciprocal here, one division per corner.
    const float* H = cam.inv;
    const float k = 1.0f / L[2];
    const float al = -L[0] * k, be = -L[1] * k, ga = -L[3] * k;
    const float nx = H[8] + H[10] * al, ny = H[9] + H[10] * be, nc = H[11] + H[10] * ga;
    const float dx = H[12] + H[14] * al, dy = H[13] + H[14] * be, dc = H[15] + H[14] * ga;
    // The four corners' depths as the lanes of one vector (each lane's
    // arithmetic that of a scalar: one division instead of four), then
    // taken in corner order.
    typedef float Float4 __attribute__((vector_size(16)));
    const float sx0 = static_cast<float>(x) * (2.0f / w) - 1.0f, sx1 = static_cast<float>(x + 1) * (2.0f / w) - 1.0f;
    const float sy0 = static_cast<float>(y) * (2.0f / h) - 1.0f, sy1 = static_cast<float>(y + 1) * (2.0f / h) - 1.0f;
    const Float4 sx = {sx0, sx1, sx0, sx1}, sy = {sy0, sy0, sy1, sy1};
    const Float4 depth = -((nx * sx + ny * sy + nc) / (dx * sx + dy * sy + dc));
    for (int corner = 0; corner < 4; ++corner) {
      float cd = depth[corner];
      if (!finite(cd)) continue;
      cd = std::min(std::max(cd, d - spread), d + spread);
      lo = std::min(lo, cd);
      hi = std::max(hi, cd);
    }
  }
  out[0] = lo;
  out[1] = hi + t;
}

// Everything about one ray that does not change along the walk (its fields:
// hiz_base.h's RayFields, which the AVX2 set-up fills). Points on the ray are
// interpolated in homogeneous form: at screen fraction t the view point is
// A(t) / B(t), with A = view / w and B = 1 / w both linear in t for any
// projective camera. `inv` holds 1 / d (0 where d is 0): a product per side
// of a box instead of a division, in the one order both backends use.
struct Ray : RayFields {
  float depth(float t) const { return -(a0[2] + t * da[2]) / (b0 + t * db); }
  // depth(t) = num(t) / b(t) with b > 0: the walk compares num with
  // range * b and never divides.
  float num(float t) const { return -(a0[2] + t * da[2]); }
  float b(float t) const { return b0 + t * db; }
  // n . (view point - P), times B(t) > 0: the plane test without a division.
  float plane(float t, const float n[3], float np) const {
    return n[0] * (a0[0] + t * da[0]) + n[1] * (a0[1] + t * da[1]) + n[2] * (a0[2] + t * da[2]) -
           np * (b0 + t * db);
  }
  // Where the line leaves the pixel box [x0, x1) x [y0, y1), as a fraction.
  float exit(const int box[4]) const {
    float te = t_end;
    if (d[0] != 0.0f)
      te = std::min(te, (static_cast<float>(d[0] > 0.0f ? box[2] : box[0]) - f0[0]) * inv[0]);
    if (d[1] != 0.0f)
      te = std::min(te, (static_cast<float>(d[1] > 0.0f ? box[3] : box[1]) - f0[1]) * inv[1]);
    return te;
  }
};

// The ray from view point `from` on the reflector, seen along `unit_from`,
// mirrored about `normal` (unit).
bool make_ray_from(const MarchSetup& s, V3 from, V3 unit_from, V3 normal, Ray& r) {
  const V3 dir = normalize(reflect(unit_from, normal));
  if (!finite(dir)) return false;
  const float len = clipped_length(s, from, dir, s.opt.max_distance);
  if (!(len > 0.0f)) return false;
  const V3 end = from + dir * len;
  const float w = static_cast<float>(s.position->width), h = static_cast<float>(s.position->height);
  float c0[4], c1[4];
  clip_of(s.proj, from, c0);
  clip_of(s.proj, end, c1);
  if (!(c0[3] > 0.0f) || !(c1[3] > 0.0f)) return false;
  // One reciprocal of w per end serves the projection and A, B alike.
  const float b0 = 1.0f / c0[3], b1 = 1.0f / c1[3];
  r.f0[0] = (c0[0] * b0 * 0.5f + 0.5f) * w;
  r.f0[1] = (c0[1] * b0 * 0.5f + 0.5f) * h;
  r.d[0] = (c1[0] * b1 * 0.5f + 0.5f) * w - r.f0[0];
  r.d[1] = (c1[1] * b1 * 0.5f + 0.5f) * h - r.f0[1];
  if (!finite(r.f0[0]) || !finite(r.f0[1]) || !finite(r.d[0]) || !finite(r.d[1])) return false;
  r.inv[0] = r.d[0] != 0.0f ? 1.0f / r.d[0] : 0.0f;
  r.inv[1] = r.d[1] != 0.0f ? 1.0f / r.d[1] : 0.0f;
  for (int k = 0; k < 2; ++k) r.nudge[k] = r.d[k] > 0.0f ? kCellNudge : (r.d[k] < 0.0f ? -kCellNudge : 0.0f);
  r.b0 = b0;
  r.db = b1 - b0;
  const float fa[3] = {from.x, from.y, from.z}, ea[3] = {end.x, end.y, end.z};
  for (int k = 0; k < 3; ++k) {
    r.a0[k] = fa[k] * b0;
    r.da[k] = ea[k] * b1 - r.a0[k];
  }
  const int image[4] = {0, 0, s.position->width, s.position->height};
  r.t_end = 1.0f;
  r.t_end = r.exit(image);
  return r.t_end > 0.0f;
}

// Pixel (x, y)'s own ray, from its centre.
bool make_ray(const MarchSetup& s, int x, int y, Ray& r) {
  V3 from, unit_from, normal;
  if (!read_origin(s, x, y, from, unit_from, normal)) return false;
  return make_ray_from(s, from, unit_from, normal, r);
}

// What a texel does to the ray between fractions ta and tb.
enum class TexelOutcome {
  Pass,     // in front of the surface, or behind its thickness: walk on
  Hit,      // crosses the surface from the front, or did so just before
            // (a late crossing): the reflection is there
  Blocked,  // inside the surface's thickness, nearer its front: most likely
            // a crossing of the front found a texel late, not sure enough for
            // a hit; the walk ends
  Entered,  // inside the thickness, nearer its back, or crossing into it from
            // behind: the ray came in through the side the camera does not
            // see (a hidden hit); the walk ends
};

// Whether the ray, where it entered texel (i, j) at fraction ta, lies in
// front of the plane of the texel it came from (true where that texel is
// unseen, has no plane, or is off the image: nothing says otherwise).
bool in_front_before(const Image& position, const HizPlanes& planes, const Ray& r, int i, int j, float ta) {
  // The cell nudge taken backwards: the texel the line was in just before.
  int pi = 0, pj = 0;
  if (!position.texel_at(r.f0[0] + ta * r.d[0] - r.nudge[0], r.f0[1] + ta * r.d[1] - r.nudge[1], pi, pj) ||
      (pi == i && pj == j))
    return true;
  const float* o = position.px(pi, pj);
  const float* n = planes.px(pi, pj);
  if (!texel_seen(o) || !normal_usable(n)) return true;
  const UnitPlane pl = unit_plane(n, o);
  return r.plane(ta, pl.u, pl.np) >= -pl.tol * r.b(ta);
}

// Where a texel and its neighbour meet at a convex crease (each centre lies
// behind the other's plane, by less than the texel's thickness: one surface
// folding away, not an outline), the surface between their centres is the
// farther of the two planes, not the texel's plane alone: a ray behind the
// texel's plane but in front of the neighbour's is in front of the surface.
// The neighbours looked at are the two across the edges nearest the ray's
// point at t0. Returns false when the ray stays in front of one of them to
// tb; else t, the first fraction from t0 at which it is behind all of them
// (t0 when it already is there).
bool behind_convex_neighbours(const Image& position, const HizPlanes& planes, const Image* back, float thickness,
                              const Ray& r, int i, int j, const UnitPlane& pl, const float* p, float t0, float tb,
                              float& t) {
  t = t0;
  const float hx = r.f0[0] + t0 * r.d[0], hy = r.f0[1] + t0 * r.d[1];
  const int nb[2][2] = {{hx < static_cast<float>(i) + 0.5f ? i - 1 : i + 1, j},
                        {i, hy < static_cast<float>(j) + 0.5f ? j - 1 : j + 1}};
  const float lim = -texel_thickness(position, back, thickness, i, j);
  for (const int* q : nb) {
    if (q[0] < 0 || q[1] < 0 || q[0] >= position.width || q[1] >= position.height) continue;
    const float* o = position.px(q[0], q[1]);
    const float* nq = planes.px(q[0], q[1]);
    if (!texel_seen(o) || !normal_usable(nq)) continue;
    const float g = pl.u[0] * (o[0] - p[0]) + pl.u[1] * (o[1] - p[1]) + pl.u[2] * (o[2] - p[2]);
    if (!(g < -pl.tol) || g < lim) continue;  // not behind this plane, or an outline
    const UnitPlane ql = unit_plane(nq, o);
    const float gq = ql.u[0] * (p[0] - o[0]) + ql.u[1] * (p[1] - o[1]) + ql.u[2] * (p[2] - o[2]);
    if (!(gq < -ql.tol)) continue;  // a concave or flat crease: this plane is the nearer
    const float qa = r.plane(t, ql.u, ql.np);
    if (qa < -ql.tol * r.b(t)) continue;  // already behind the neighbour's plane
    const float qb = r.plane(tb, ql.u, ql.np);
    if (!(qb < -ql.tol * r.b(tb))) return false;  // in front of it to the texel's exit
    t = t + (tb - t) * std::min(std::max(qa / (qa - qb), 0.0f), 1.0f);
  }
  return true;
}

// Whether the ray at fraction t lies further from texel (i, j)'s own depth,
// in front or behind, than kCrossingDepth times the texel's thickness: then
// it is off the object there, and a crossing of the texel's plane, or being
// behind it, is not a crossing of its surface or being inside it. At a
// rounded object's outline the thickness falls to 0 while the tangent plane
// turns edge-on and spans metres of depth across the texel: rays passing in
// front of the object or behind it cross that plane. `pz`: the texel's view
// z; `tk`: its thickness (0 or less: none known, and nothing is off).
bool off_the_object(const Ray& r, float pz, float tk, float t) {
  return tk > 0.0f && std::fabs(r.depth(t) + pz) > kCrossingDepth * tk;
}

// The ray crosses the texel's plane from the front (t_hit: that crossing),
// or it is behind the plane at the texel, where the texel's thickness says
// whether that is solid. Being behind by no more than a rounding slack is a
// crossing found one texel late, and counts as a hit. `planes`: the plane
// normals (hiz_plane_normals_row()). `located`: the hit was found on the texel's
// plane (else only to the texel).
TexelOutcome texel_hit(const MarchSetup& s, const HizPlanes& planes, const HizCamera& cam, const Image* back,
                       const Ray& r, int i, int j, float ta, float tb, float& t_hit, bool& located) {
  const Image& position = *s.position;
  const float* n = planes.px(i, j);
  t_hit = ta;
  located = false;
  if (!normal_usable(n)) return TexelOutcome::Hit;  // no plane: the depth span decided
  const float* p = position.px(i, j);
  const UnitPlane pl = unit_plane(n, p);
  const float ga = r.plane(ta, pl.u, pl.np), gb = r.plane(tb, pl.u, pl.np);
  const bool a_behind = ga < -pl.tol * r.b(ta), b_behind = gb < -pl.tol * r.b(tb);
  if (!a_behind && !b_behind) return TexelOutcome::Pass;
  if (!a_behind) {
    const float f = ga / (ga - gb);  // G is linear in t: its zero, in [0, 1]
    t_hit = ta + (tb - ta) * std::min(std::max(f, 0.0f), 1.0f);
    located = true;
    float t;
    if (!behind_convex_neighbours(position, planes, back, s.opt.thickness, r, i, j, pl, p, t_hit, tb, t))
      return TexelOutcome::Pass;
    t_hit = t;
    // Only the back layer's thickness bounds a crossing: a grazing plane's
    // depth spread across one texel can exceed a guessed one.
    if (off_the_object(r, p[2], known_thickness(position, back, i, j), t_hit)) return TexelOutcome::Pass;
    return TexelOutcome::Hit;
  }
  // Behind the plane from the start, but maybe in front of a convex
  // neighbour's: then it meets the surface only where it is behind both.
  {
    float t;
    if (!behind_convex_neighbours(position, planes, back, s.opt.thickness, r, i, j, pl, p, ta, tb, t))
      return TexelOutcome::Pass;
    if (t > ta) {
      if (!(r.plane(t, pl.u, pl.np) < -pl.tol * r.b(t))) return TexelOutcome::Pass;  // back in front by then
      if (off_the_object(r, p[2], known_thickness(position, back, i, j), t)) return TexelOutcome::Pass;
      t_hit = t;
      located = true;
      return TexelOutcome::Hit;
    }
  }
  // Behind from the start: how far, in view distance, at either end. Not
  // inside the object, though, when far from the texel's own depth
  // (off_the_object(): behind an edge-on plane is not behind the surface),
  // by the thickness the tests below take, guessed or known.
  const float thick = texel_thickness(position, back, s.opt.thickness, i, j);
  if (off_the_object(r, p[2], thick, ta)) return TexelOutcome::Pass;
  float L[4];
  if (!texel_plane(position, planes, cam, i, j, L)) return TexelOutcome::Hit;
  const float w = static_cast<float>(position.width), h = static_cast<float>(position.height);
  auto behind_by = [&](float t) {
    const float sx = (r.f0[0] + t * r.d[0]) * (2.0f / w) - 1.0f;
    const float sy = (r.f0[1] + t * r.d[1]) * (2.0f / h) - 1.0f;
    return r.depth(t) - plane_depth(cam.inv, L, sx, sy);
  };
  const float slack = kBehindSlack * std::fabs(p[2]);
  const float da = behind_by(ta);
  if (da <= slack) {
    located = true;  // on the plane, to the rounding slack
    return TexelOutcome::Hit;
  }
  // Which side the ray came in by: the one it is nearer to, measured from the
  // texel's own depth, not along its plane. A crossing of the front found late
  // lies just behind it; a ray that passed behind the object the texel before
  // and is inside now came in by the back. Flat, because near an outline the
  // plane runs in front of a rounded object (the surface curves away from it),
  // while the middle of the front and back depths is where the two sides meet
  // at the outline (for a sphere, exactly the outline's depth).
  if (da <= thick) {
    if (r.depth(ta) + p[2] > kHiddenShare * thick) return TexelOutcome::Entered;
    // Nearer the front: most likely a crossing found late. Sure enough to be
    // reported as a hit where the ray entered the texel when the back-face
    // layer gives the thickness (a guessed one also takes rays that pass
    // behind thin things), the ray stays behind the plane to the texel's exit
    // (one that comes back out in front grazed an edge), and it was in front
    // of the surface of the texel it came from (behind it, it came from behind
    // things). docs/hiz.md, *Late crossings*.
    if (b_behind && known_thickness(position, back, i, j) > 0.0f && in_front_before(position, planes, r, i, j, ta)) {
      located = true;
      return TexelOutcome::Hit;
    }
    return TexelOutcome::Blocked;
  }
  if (b_behind && behind_by(tb) <= thick) return TexelOutcome::Entered;
  return TexelOutcome::Pass;
}

// How sure a hit at (hx, hy) pixels in texel (i, j) is to lie on the texel's
// object. The texel is on an outline when a neighbour across one of its edges
// is unseen or lies behind its plane by more than its thickness: its plane
// then covers its whole footprint, although the object's edge lies somewhere
// between its centre (the object: that is where it was sampled) and the
// neighbour's. With that edge anywhere in between, a hit d texels from the
// centre toward such a neighbour is on the object with probability 1 - d:
// 1 on the inner half, falling to kUncertain at the texel's outer edge.
//
// The back-face layer can place the edge (docs/hiz.md, *Visibility*): a
// closed object's thickness along the view ray falls to 0 at its outline.
// A mesh's outline runs along edges where a front and a back face meet, a
// wedge, across which the thickness falls linearly: extrapolated from the
// texel and the one opposite the outline, it reaches 0 at
// s = t / (t_in - t) texels past the centre, and a hit before that is on the
// object (confidence 1 from that side). Where the thickness does not fall
// toward the outline (a box's flat side) nothing is placed and the rule above
// stays.
float outline_confidence(const Image& position, const HizPlanes& normal, const Image* back, float thickness,
                         int i, int j, float hx, float hy) {
  const float* p = position.px(i, j);
  const float* n = normal.px(i, j);
  const float th = texel_thickness(position, back, thickness, i, j);
  const float lim = -th * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  const float dx = hx - (static_cast<float>(i) + 0.5f), dy = hy - (static_cast<float>(j) + 0.5f);
  const int nb[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
  const float toward[4] = {-dx, dx, -dy, dy};
  const float t = known_thickness(position, back, i, j);
  auto inside = [&](const int* q) { return q[0] >= 0 && q[1] >= 0 && q[0] < position.width && q[1] < position.height; };
  auto across = [&](const int* q) {  // unseen, or behind the plane by more than the thickness
    const float* o = position.px(q[0], q[1]);
    const float g = n[0] * (o[0] - p[0]) + n[1] * (o[1] - p[1]) + n[2] * (o[2] - p[2]);
    return !(texel_seen(o) && g >= lim);
  };
  float c = 1.0f;
  for (int k = 0; k < 4; ++k) {
    const int* q = nb[k];
    if (!inside(q) || !across(q)) continue;
    const float d = std::min(std::max(toward[k], 0.0f), 0.5f);
    const int* in = nb[k ^ 1];  // the neighbour opposite the outline
    if (t > 0.0f && inside(in) && !across(in)) {
      const float t_in = known_thickness(position, back, in[0], in[1]);
      if (t_in > t && d * (t_in - t) <= t) continue;  // before the placed edge: on the object
    }
    c = std::min(c, 1.0f - 2.0f * (1.0f - kUncertain) * d);
  }
  return c;
}

// Confidence times the fade at the screen's edges, for a hit at (u, v) of
// pixel (x, y)'s ray (the fade looks at the edge the ray is heading for).
inline float hit_visibility(const Image& image, int x, int y, float u, float v, float confidence) {
  return confidence * hiz::pixel_edge_fade(x, y, image.width, image.height, u, v);
}

// Rays made at a time (hiz_pixel_rays()): enough for the AVX2 set-up's
// lanes, few enough that they stay in the L1 cache until their walks start.
constexpr int kRayChunk = 64;

// A queue of pixels for hiz_walk() to trace, and the scalar parts of their
// walks: each ray, made a chunk at a time, and the texel test where a lane's
// walk stops at level 0.
struct PixelQueue {
  const TraceInputs& in;
  const MarchSetup& s;
  const HizPlanes& planes;
  const HizCamera& cam;
  Image& out;
  WalkIsa isa = WalkIsa::Scalar;
  int y = 0;
  // The pixels of row y that walk (hiz_row_jobs()): xs[0 .. count), the rays of
  // xs[chunk_begin .. chunk_end) in `rays` where `made`.
  const int* xs = nullptr;
  int count = 0, next = 0, chunk_begin = 0, chunk_end = 0;
  RayFields rays[kRayChunk] = {};
  unsigned char made[kRayChunk] = {};
  // The outline samples of row y (sample_start()): `per_pixel` rays for each
  // pixel edges[0..), into samples[4 * job].
  const int* edges = nullptr;
  int job = 0, jobs = 0, per_pixel = 0;
  float* samples = nullptr;
  Ray ray[kWalkLanes] = {};
  float* dst[kWalkLanes] = {};  // where each lane's answer goes
  int px[kWalkLanes] = {};      // and the column of the pixel it is for (row y)
};

// The walk of ray r from pixel (x, y): it leaves the origin's own texel
// first, since the ray starts on that texel's surface.
WalkRay walk_from(const Ray& r, int x, int y) {
  const int box[4] = {x, y, x + 1, y + 1};
  const float t = r.exit(box);
  return WalkRay{{r.f0[0], r.f0[1]}, {r.d[0], r.d[1]}, {r.inv[0], r.inv[1]}, {r.nudge[0], r.nudge[1]},
                 r.a0[2], r.da[2], r.b0, r.db, r.t_end, t, r.num(t), r.b(t)};
}

bool queue_start(void* ctx, int lane, WalkRay& w) {
  PixelQueue& q = *static_cast<PixelQueue*>(ctx);
  while (q.next < q.count) {
    if (q.next == q.chunk_end) {
      q.chunk_begin = q.next;
      q.chunk_end = std::min(q.count, q.next + kRayChunk);
      hiz_pixel_rays(q.s, q.y, q.xs + q.chunk_begin, q.chunk_end - q.chunk_begin, q.isa, q.rays, q.made);
    }
    const int k = q.next++ - q.chunk_begin;
    if (!q.made[k]) continue;
    const int x = q.xs[q.chunk_begin + k];
    Ray& r = q.ray[lane];
    static_cast<RayFields&>(r) = q.rays[k];
    q.dst[lane] = q.out.px(x, q.y);
    q.px[lane] = x;
    w = walk_from(r, x, q.y);
    return true;
  }
  return false;
}

bool queue_texel(void* ctx, int lane, int i, int j, float ta, float tb) {
  PixelQueue& q = *static_cast<PixelQueue*>(ctx);
  const Ray& r = q.ray[lane];
  const Image& pos = *q.s.position;
  const Image* back = q.in.back_position;
  float th;
  bool located;
  const TexelOutcome hit = texel_hit(q.s, q.planes, q.cam, back, r, i, j, ta, tb, th, located);
  if (hit == TexelOutcome::Pass) return true;
  float* out = q.dst[lane];
  if (hit == TexelOutcome::Blocked || hit == TexelOutcome::Entered) {
    // What hides the hit: the colour stages may show it in place of the
    // sky (docs/hiz.md, "Blocked rays"). The texel's centre, not where
    // the ray entered it: a bilinear read on its edge would mix in the
    // texel beside it, often another object.
    if (q.s.opt.blocked != Blocked::Occluder) return false;
    const float u = (static_cast<float>(i) + 0.5f) / static_cast<float>(pos.width);
    const float v = (static_cast<float>(j) + 0.5f) / static_cast<float>(pos.height);
    out[0] = u;
    out[1] = v;
    out[2] = hit_visibility(pos, q.px[lane], q.y, u, v, 1.0f);
    out[3] = hit == TexelOutcome::Entered ? kEnteredHidden : 0.0f;
    return false;
  }
  const float hx = r.f0[0] + th * r.d[0], hy = r.f0[1] + th * r.d[1];
  const float u = hx / static_cast<float>(pos.width);
  const float v = hy / static_cast<float>(pos.height);
  if (!finite(u) || !finite(v)) return false;
  const float confidence = located ? outline_confidence(pos, q.planes, back, q.s.opt.thickness, i, j, hx, hy) : kUncertain;
  out[0] = u;
  out[1] = v;
  out[2] = out[3] = hit_visibility(pos, q.px[lane], q.y, u, v, confidence);
  return false;
}

}  // namespace

HizCamera hiz_camera(const Mat4& projection) {
  const Mat4 inv = inverse(projection);
  HizCamera cam;
  for (int k = 0; k < 16; ++k) cam.inv[k] = static_cast<float>(inv.m[k]);
  return cam;
}

HizPyramid build_hiz_pyramid(const Image& position, const Image& normal, const Image* back_position,
                             const HizCamera& cam, float thickness, int threads, HizPlanes& planes,
                             WalkIsa isa) {
  HizPyramid p;
  int w = position.width, h = position.height;
  size_t cells = 0;
  for (;;) {
    p.width.push_back(w);
    p.height.push_back(h);
    p.offset.push_back(cells);
    cells += static_cast<size_t>(w) * h;
    if (w == 1 && h == 1) break;
    w = std::max(1, w / 2);
    h = std::max(1, h / 2);
  }
  p.levels = static_cast<int>(p.width.size());
  p.range.resize(cells * 2);
  planes.width = position.width;
  planes.height = position.height;
  planes.xyz.resize(position.pixel_count() * 3);
  // Blocks of rows, each with the seen flags of its rows and the two on
  // either side that the plane normals look at.
  constexpr int kBlock = 16;
  const int height = position.height;
  parallel_rows(0, (height + kBlock - 1) / kBlock, threads, [&](int b) {
    const int y0 = b * kBlock, y1 = std::min(height, y0 + kBlock);
    SeenRows seen;
    fill_seen_rows(position, std::max(0, y0 - 2), std::min(height, y1 + 2), seen, isa);
    for (int y = y0; y < y1; ++y) {
      hiz_plane_normals_row(position, normal, seen, y, planes, isa);
      float* row = p.range.data() + static_cast<size_t>(y) * position.width * 2;
      int x = 0;
#if defined(GLINT_WALK_AVX2)
      if (isa == WalkIsa::Avx2) {
        BaseRow r;
        r.position = position.px(0, y);
        r.planes = planes.px(0, y);
        r.back = back_position ? back_position->px(0, y) : nullptr;
        r.seen = seen.bytes.data() + static_cast<size_t>(y - seen.y0) * seen.width;
        r.inv = cam.inv;
        r.thickness = thickness;
        r.footprint_spread = kFootprintSpread;
        r.width = position.width;
        r.height = position.height;
        r.y = y;
        r.out = row;
        x = hiz_base_row_avx2(r);
      }
#endif
      for (; x < position.width; ++x)
        base_range(position, planes, back_position, cam, thickness, seen.at(x, y), x, y, row + 2 * x);
    }
  });
  for (int l = 1; l < p.levels; ++l) {
    const int pw = p.width[l - 1], ph = p.height[l - 1];
    parallel_rows(0, p.height[l], threads, [&](int j) {
      // The last cell of a row or column also takes what an odd size leaves.
      const int y0 = 2 * j, y1 = j == p.height[l] - 1 ? ph - 1 : std::min(2 * j + 1, ph - 1);
      int i = 0;
      if (y1 == y0 + 1) {
        // Whole 2x2 blocks: the general loop's comparisons in its order,
        // without its per-cell bounds and loops (this function's own
        // instructions at 1080p: 73 M before, 23 M after).
        const float* r0 = p.cell(l - 1, 0, y0);
        const float* r1 = p.cell(l - 1, 0, y1);
        float* o = p.cell(l, 0, j);
        for (; i < p.width[l] - 1; ++i) {
          const float* a = r0 + 4 * i;
          const float* b = r1 + 4 * i;
          o[2 * i] = std::min(std::min(std::min(std::min(kInf, a[0]), a[2]), b[0]), b[2]);
          o[2 * i + 1] = std::max(std::max(std::max(std::max(-kInf, a[1]), a[3]), b[1]), b[3]);
        }
      }
      for (; i < p.width[l]; ++i) {
        const int x0 = 2 * i, x1 = i == p.width[l] - 1 ? pw - 1 : std::min(2 * i + 1, pw - 1);
        float lo = kInf, hi = -kInf;
        for (int yy = y0; yy <= y1; ++yy)
          for (int xx = x0; xx <= x1; ++xx) {
            const float* c = p.cell(l - 1, xx, yy);
            lo = std::min(lo, c[0]);
            hi = std::max(hi, c[1]);
          }
        float* o = p.cell(l, i, j);
        o[0] = lo;
        o[1] = hi;
      }
    });
  }
  return p;
}

namespace {

// --- Antialiased outlines (docs/hiz.md) --------------------------------

// The ray of pixel (x, y) from offset (ox, oy) pixels off its centre: from
// where the view ray through that point meets the texel's tangent plane,
// mirrored about the pixel's shading normal. False where the plane is seen
// edge-on or the point would leave the texel's depth range (base_range()).
bool subpixel_ray(const MarchSetup& s, const HizPlanes& planes, const HizCamera& cam, int x, int y, float ox,
                  float oy, Ray& r) {
  V3 from, unit_from, normal;
  if (!read_origin(s, x, y, from, unit_from, normal)) return false;
  float L[4];
  if (!texel_plane(*s.position, planes, cam, x, y, L)) return false;
  const float w = static_cast<float>(s.position->width), h = static_cast<float>(s.position->height);
  const float sx = (static_cast<float>(x) + (0.5f + ox)) * (2.0f / w) - 1.0f;
  const float sy = (static_cast<float>(y) + (0.5f + oy)) * (2.0f / h) - 1.0f;
  const float sz = -(L[0] * sx + L[1] * sy + L[3]) / L[2];
  const float* H = cam.inv;
  float v[4];
  for (int k = 0; k < 4; ++k) v[k] = H[4 * k] * sx + H[4 * k + 1] * sy + H[4 * k + 2] * sz + H[4 * k + 3];
  const V3 at{v[0] / v[3], v[1] / v[3], v[2] / v[3]};
  const float d = -from.z;
  if (!finite(at) || !(std::fabs(-at.z - d) <= kFootprintSpread * std::fabs(d))) return false;
  if (!incident_direction(s, at, unit_from)) return false;
  return make_ray_from(s, at, unit_from, normal, r);
}

// The walk's start for the outline samples: job j is sample j % per_pixel of
// pixel edges[j / per_pixel] in row y. A sample without a ray of its own
// keeps the centre's report.
bool sample_start(void* ctx, int lane, WalkRay& w) {
  PixelQueue& q = *static_cast<PixelQueue*>(ctx);
  while (q.job < q.jobs) {
    if (q.job == q.chunk_end) {
      // The next kRayChunk samples' rays, made together (hiz_sample_rays()).
      q.chunk_begin = q.job;
      q.chunk_end = std::min(q.jobs, q.job + kRayChunk);
      int xs[kRayChunk];
      float offsets[2 * kRayChunk];
      for (int j = q.chunk_begin; j < q.chunk_end; ++j) {
        const int k = j % q.per_pixel, c = j - q.chunk_begin;
        xs[c] = q.edges[j / q.per_pixel];
        offsets[2 * c] = kAaOffset[k][0];
        offsets[2 * c + 1] = kAaOffset[k][1];
      }
      hiz_sample_rays(q.s, q.planes, q.cam, q.y, xs, offsets, q.chunk_end - q.chunk_begin, q.isa, q.rays,
                      q.made);
    }
    const int j = q.job++;
    const int x = q.edges[j / q.per_pixel], c = j - q.chunk_begin;
    float* o = q.samples + static_cast<size_t>(j) * 4;
    const float* centre = q.out.px(x, q.y);
    o[0] = centre[0], o[1] = centre[1], o[2] = centre[2], o[3] = centre[3];
    if (!q.made[c]) continue;
    o[0] = o[1] = o[2] = o[3] = 0.0f;
    Ray& r = q.ray[lane];
    static_cast<RayFields&>(r) = q.rays[c];
    q.dst[lane] = o;
    q.px[lane] = x;
    w = walk_from(r, x, q.y);
    return true;
  }
  return false;
}

#if defined(GLINT_WALK_AVX2)
RayRow ray_row(const MarchSetup& s, int y) {
  RayRow r;
  r.position = s.position->px(0, y);
  r.normal = s.normal->px(0, y);
  r.proj = s.proj;
  r.projd = s.projd;
  r.eye_kind = static_cast<int>(s.eye_kind);
  for (int c = 0; c < 3; ++c) r.eye[c] = s.eye[c];
  r.max_distance = s.opt.max_distance;
  r.cell_nudge = kCellNudge;
  r.width = s.position->width;
  r.height = s.position->height;
  r.y = y;
  return r;
}
#endif

// The pixels' own rays (offsets null) or the outline samples'.
void rays_of(const MarchSetup& s, const HizPlanes* planes, const HizCamera* cam, int y, const int* xs,
             const float* offsets, int n, WalkIsa isa, RayFields* rays, unsigned char* made) {
#if defined(GLINT_WALK_AVX2)
  if (isa == WalkIsa::Avx2) {
    RayRow r = ray_row(s, y);
    if (offsets) {
      r.offset = offsets;
      r.planes = planes->px(0, y);
      r.inv = cam->inv;
      r.footprint_spread = kFootprintSpread;
    }
    hiz_pixel_rays_avx2(r, xs, n, rays, made);
    return;
  }
#else
  (void)isa;
#endif
  for (int k = 0; k < n; ++k) {
    Ray ray;
    made[k] = offsets ? subpixel_ray(s, *planes, *cam, xs[k], y, offsets[2 * k], offsets[2 * k + 1], ray)
                      : make_ray(s, xs[k], y, ray);
    if (made[k]) rays[k] = ray;
  }
}
}  // namespace

void hiz_pixel_rays(const MarchSetup& s, int y, const int* xs, int n, WalkIsa isa, RayFields* rays,
                    unsigned char* made) {
  rays_of(s, nullptr, nullptr, y, xs, nullptr, n, isa, rays, made);
}

void hiz_sample_rays(const MarchSetup& s, const HizPlanes& planes, const HizCamera& cam, int y, const int* xs,
                     const float* offsets, int n, WalkIsa isa, RayFields* rays, unsigned char* made) {
  rays_of(s, &planes, &cam, y, xs, offsets, n, isa, rays, made);
}

Image trace_hiz(const TraceInputs& in, const TraceOptions& opt, int threads) {
  return trace_hiz(in, opt, threads, hiz_walk_default());
}

Image trace_hiz(const TraceInputs& in, const TraceOptions& opt, int threads, WalkIsa isa) {
  Image out = Image::uninitialized(in.position.width, in.position.height);  // the queues answer each pixel
  const HizCamera cam = hiz_camera(in.projection);
  HizPlanes planes;
  const HizPyramid pyr =
      build_hiz_pyramid(in.position, in.normal, in.back_position, cam, opt.thickness, threads, planes, isa);
  const MarchSetup setup = make_setup(in.position, in.normal, in.projection, opt, nullptr);
  // The walk's kernels index cells with ints (a 46k x 46k image would not fit).
  if (pyr.range.size() / 2 > static_cast<size_t>(std::numeric_limits<int>::max()))
    throw InvalidArgument("position", "too large for the hiz march: more than 2^31 pyramid cells");
  int offset[kMaxLevels];
  for (int l = 0; l < pyr.levels; ++l) offset[l] = static_cast<int>(pyr.offset[l]);
  WalkPyramid walk;
  walk.levels = pyr.levels;
  walk.width = in.position.width;
  walk.height = in.position.height;
  walk.range = pyr.range.data();
  walk.offset = offset;
  walk.texel[0] = planes.xyz.data();
  walk.floats[0] = 3;
  walk.texel[1] = in.position.data.data();
  walk.floats[1] = 4;
  // `steps` cells per level (kMaxSteps x kMaxLevels fits an int).
  const int budget = static_cast<int>(std::min<long>(static_cast<long>(opt.steps) * pyr.levels,
                                                     std::numeric_limits<int>::max()));
  // One queue per row (or pass of a row), walked a kernel's lanes at a time.
  auto walk_row = [&](int y, int x0, int step, bool reuse) {
    std::vector<unsigned char> reusable;
    if (reuse) {
      reusable.resize(static_cast<size_t>(out.width));
      hiz_reuse_surface_row(in, y, isa, reusable.data());
    }
    std::vector<int> xs;
    hiz_row_jobs(in, out, y, x0, step, reuse ? reusable.data() : nullptr, xs);
    PixelQueue q{in, setup, planes, cam, out};
    q.isa = isa;
    q.y = y;
    q.xs = xs.data();
    q.count = static_cast<int>(xs.size());
    WalkHost host;
    host.ctx = &q;
    host.start = queue_start;
    host.texel = queue_texel;
    hiz_walk(walk, host, budget, isa);
  };
  if (!hiz_reuses_rays(opt)) {
    parallel_rows(0, out.height, threads, [&](int y) { walk_row(y, 0, 1, false); });
  } else {
    // Every other pixel of every other row first; then the rest, from them.
    parallel_rows(0, (out.height + 1) / 2, threads, [&](int j) { walk_row(2 * j, 0, 2, false); });
    parallel_rows(0, out.height, threads,
                  [&](int y) { walk_row(y, (y & 1) ? 0 : 1, (y & 1) ? 1 : 2, true); });
  }
  if (opt.antialias <= 0) return out;
  // The outlines: found on the whole frame first, then each row's samples
  // walked and resolved (a row writes only its own pixels, which no other
  // row reads by then).
  std::vector<std::vector<unsigned char>> beside_hidden;
  const std::vector<std::vector<int>> edges = outline_pixels(in, out, threads, &beside_hidden);
  const int k = std::min(opt.antialias, 4);
  const float w = static_cast<float>(out.width), h = static_cast<float>(out.height);
  parallel_rows(0, out.height, threads, [&](int y) {
    const std::vector<int>& row = edges[y];
    if (row.empty()) return;
    std::vector<float> samples(row.size() * static_cast<size_t>(k) * 4);
    PixelQueue q{in, setup, planes, cam, out};
    q.isa = isa;
    q.y = y;
    q.edges = row.data();
    q.jobs = static_cast<int>(row.size()) * k;
    q.per_pixel = k;
    q.samples = samples.data();
    WalkHost host;
    host.ctx = &q;
    host.start = sample_start;
    host.texel = queue_texel;
    hiz_walk(walk, host, budget, isa);
    for (size_t e = 0; e < row.size(); ++e) {
      float* o = out.px(row[e], y);
      resolve_outline(o, samples.data() + e * static_cast<size_t>(k) * 4, k, w, h, o, beside_hidden[y][e] != 0);
    }
  });
  return out;
}

}  // namespace glint::cpu
