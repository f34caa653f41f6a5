// The hiz walk (hiz_walk.h) for x86-64 CPUs with AVX2: sixteen rays at
// once, two groups of eight lanes of ymm registers. This file alone is built
// with -mavx2, and hiz_walk.cpp calls it only where the CPU has AVX2. Not
// -mfma: contracted products would round differently from the scalar walk
// and the shaders. It includes nothing with inline functions of its own and
// keeps its helpers in an anonymous namespace, so that the linker is never
// handed an AVX2 copy of a function the rest of the library calls on a
// machine without AVX2.
//
// Each lane runs the walk of hiz_walk_scalar() (hiz_walk.cpp) on one ray,
// with the same float operations in the same order, so a lane's answer is
// the scalar walk's bit for bit, and hiz_walk.glsl's as before. A step, per
// lane:
//
//   - the cell of the current level the ray is in just past t (nudged along
//     its direction), and the fraction te where it leaves that cell;
//   - if the ray's depth span over [t, te] misses the cell's range: move to
//     te, clear the known bits of the levels whose cells it left there, and
//     go up a level unless the cell above is known to overlap;
//   - if it overlaps above level 0: note the level as known, go down;
//   - at level 0: the texel test, which is the caller's (scalar, rare).
//
// A lane whose ray ended (a hit, a miss, out of steps or of screen) takes
// the queue's next ray at the top of the next step, so the lanes stay full
// until the queue runs dry.
//
// Why two groups: a group's step is one chain (the cell from t, its range
// gathered, the overlap, the next t) that mostly waits, on the gathers
// above all. The two groups' steps are independent, and made side by side
// (both located, then both advanced), the core runs one while the other
// waits: 9-10% less time for a single-thread 1080p trace. Three or four
// groups measured no better than two.
#include <immintrin.h>

#include "hiz_walk.h"

#if !defined(__AVX2__)
#error "hiz_walk_avx2.cpp is built with -mavx2"
#endif

namespace glint::cpu {
namespace {

constexpr int N = 8;  // one ymm register per vector
constexpr int kGroups = 2;
static_assert(N * kGroups <= kWalkLanes, "the caller keeps kWalkLanes rays");
typedef float VF __attribute__((vector_size(4 * N)));
typedef int VI __attribute__((vector_size(4 * N)));
typedef unsigned VU __attribute__((vector_size(4 * N)));
constexpr unsigned kAllLanes = (1u << N) - 1u;

// Bit k set where lane k of mask m (all ones or zero) is set.
__attribute__((always_inline)) inline unsigned lane_bits(VI m) {
  return static_cast<unsigned>(_mm256_movemask_ps(reinterpret_cast<__m256>(m)));
}

// Each lane's level's first cell, from the table of levels. (Two in-register
// permutes of a 16-level table instead measured no faster.)
__attribute__((always_inline)) inline VI level_offset(const int* offset, VI level) {
  return reinterpret_cast<VI>(_mm256_i32gather_epi32(offset, reinterpret_cast<__m256i>(level), 4));
}

// The (nearest, farthest) pair of each lane's cell. Scale 8: a cell is two
// floats, so the index stays the cell's own.
__attribute__((always_inline)) inline void cell_range(const float* range, VI cell, VF& lo, VF& hi) {
  lo = reinterpret_cast<VF>(_mm256_i32gather_ps(range, reinterpret_cast<__m256i>(cell), 8));
  hi = reinterpret_cast<VF>(_mm256_i32gather_ps(range + 1, reinterpret_cast<__m256i>(cell), 8));
}

// std::nextafter(t, +inf) for the values a running ray's t takes (finite,
// below 1): the next float up. On unsigned bits: a vector select computes
// both sides in every lane, and -0's bits minus one would overflow an int.
__attribute__((always_inline)) inline VF next_up(VF t) {
  const VU bits = reinterpret_cast<VU>(t);
  const VU one = VU{} + 1u;
  const VU up = t > 0.0f ? bits + one : (t < 0.0f ? bits - one : one);
  return reinterpret_cast<VF>(up);
}

// The rays of one group of lanes. Lanes without a ray keep level 0 and t 0,
// so that their cells (computed and ignored) stay inside the pyramid.
struct Lanes {
  VF f0x, f0y, dx, dy, ix, iy, nx, ny;
  VF a0z, daz, b0, db, t_end;
  VF t, nt, bt;
  VI level, it, alive;
  VU known;
  int first;  // the caller's lane of lane 0
  bool live;  // rays left in it, or the queue may have more
};

// What one step of a group computes before the texel tests.
struct Step {
  VI run, i, j, bx, by, movex, movey;
  VF vx, vy, te, ne, be;
  VI overlap;
};

// Rays out of steps or past the screen's edge end here (their answer is the
// miss already written); empty lanes take the next rays. False when the
// group has no ray left.
__attribute__((always_inline)) inline bool refill(Lanes& g, const WalkHost& host, int budget, bool& open,
                                                  VI& run) {
  run = g.alive & (g.it < budget) & (g.t < g.t_end);
  if (lane_bits(run) == kAllLanes) return true;
  g.alive = run;
  unsigned empty = ~lane_bits(g.alive) & kAllLanes;
  while (empty && open) {
    const int k = __builtin_ctz(empty);
    WalkRay r;
    if (!host.start(host.ctx, g.first + k, r)) {
      open = false;
      break;
    }
    if (!(r.t < r.t_end)) continue;  // left the screen with its own texel
    g.f0x[k] = r.f0[0];
    g.f0y[k] = r.f0[1];
    g.dx[k] = r.d[0];
    g.dy[k] = r.d[1];
    g.ix[k] = r.inv[0];
    g.iy[k] = r.inv[1];
    g.nx[k] = r.nudge[0];
    g.ny[k] = r.nudge[1];
    g.a0z[k] = r.a0z;
    g.daz[k] = r.daz;
    g.b0[k] = r.b0;
    g.db[k] = r.db;
    g.t_end[k] = r.t_end;
    g.t[k] = r.t;
    g.nt[k] = r.nt;
    g.bt[k] = r.bt;
    g.level[k] = 0;
    g.known[k] = 0;
    g.it[k] = 0;
    g.alive[k] = -1;
    empty &= empty - 1;
  }
  run = g.alive;
  return lane_bits(run) != 0;
}

// The cell each lane's ray is in just past t (as hiz_walk_scalar(), with its
// two branches as a clamp: the first cell where the line is not past 0 or
// not a number, the last where it is at or past the far side), where it
// leaves it, and whether its depth span there meets the cell's range.
__attribute__((always_inline)) inline void locate(const Lanes& g, const WalkPyramid& pyr, Step& s) {
  const VI zero = {};
  const VF fzero = {};
  const VI width = zero + pyr.width, height = zero + pyr.height;
  const VI level = g.level;
  const VF px = g.f0x + g.t * g.dx + g.nx, py = g.f0y + g.t * g.dy + g.ny;
  const VF scale = reinterpret_cast<VF>((127 - level) << 23);  // 1 / 2^level, exactly
  const VF sx = px * scale, sy = py * scale;
  VI wl = width >> level, hl = height >> level;
  wl = wl < 1 ? zero + 1 : wl;
  hl = hl < 1 ? zero + 1 : hl;
  const VF wl1 = __builtin_convertvector(wl - 1, VF), hl1 = __builtin_convertvector(hl - 1, VF);
  VF cx = sx > 0.0f ? sx : fzero, cy = sy > 0.0f ? sy : fzero;
  cx = cx < wl1 ? cx : wl1;
  cy = cy < hl1 ? cy : hl1;
  const VI i = __builtin_convertvector(cx, VI), j = __builtin_convertvector(cy, VI);
  // The cell's sides on the ray's way, and where it crosses them.
  const VI bx = g.dx > 0.0f ? (i == wl - 1 ? width : (i + 1) << level) : i << level;
  const VI by = g.dy > 0.0f ? (j == hl - 1 ? height : (j + 1) << level) : j << level;
  const VF vx = (__builtin_convertvector(bx, VF) - g.f0x) * g.ix;
  const VF vy = (__builtin_convertvector(by, VF) - g.f0y) * g.iy;
  const VI movex = g.dx != 0.0f, movey = g.dy != 0.0f;
  VF te = g.t_end;
  te = (movex & (vx < te)) ? vx : te;
  te = (movey & (vy < te)) ? vy : te;
  te = te > g.t ? te : next_up(g.t);  // always move on
  const VF ne = -(g.a0z + te * g.daz), be = g.b0 + te * g.db;
  VF c0, c1;
  cell_range(pyr.range, level_offset(pyr.offset, level) + j * wl + i, c0, c1);
  // The depth span [min, max] of the two ends meets [c0, c1].
  s.overlap = ((g.nt >= c0 * g.bt) | (ne >= c0 * be)) & ((g.nt <= c1 * g.bt) | (ne <= c1 * be));
  s.i = i, s.j = j, s.bx = bx, s.by = by, s.movex = movex, s.movey = movey;
  s.vx = vx, s.vy = vy, s.te = te, s.ne = ne, s.be = be;
}

// The rest of the step: level-0 texels the span meets go to the caller's
// plane test, lane by lane; then each lane goes down, moves on, or ends.
__attribute__((always_inline)) inline void advance(Lanes& g, const WalkPyramid& pyr, const WalkHost& host,
                                                   const Step& s) {
  const VI zero = {};
  const int top = pyr.levels - 1;
  const VI run = s.run, overlap = s.overlap;
  VI pass = zero;
  for (unsigned test = lane_bits(run & overlap & (g.level == 0)); test; test &= test - 1) {
    const int k = __builtin_ctz(test);
    if (host.texel(host.ctx, g.first + k, s.i[k], s.j[k], g.t[k], s.te[k]))
      pass[k] = -1;
    else
      g.alive[k] = 0;
  }
  const VI down = run & overlap & (g.level > 0);
  const VI move = run & (~overlap | pass);
  g.known = down ? g.known | (VU{} + 1u) << reinterpret_cast<VU>(g.level) : g.known;
  g.level = down ? g.level - 1 : g.level;
  for (unsigned m = lane_bits(down & (g.level == 0)); m; m &= m - 1) {
    const int k = __builtin_ctz(m);
    const long x0 = 2 * s.i[k] < pyr.width ? 2 * s.i[k] : pyr.width - 1;
    const long y0 = 2 * s.j[k] < pyr.height ? 2 * s.j[k] : pyr.height - 1;
    const long y1 = y0 + 1 < pyr.height ? y0 + 1 : y0;
    for (int b = 0; b < 2; ++b) {
      __builtin_prefetch(pyr.texel[b] + (y0 * pyr.width + x0) * pyr.floats[b]);
      __builtin_prefetch(pyr.texel[b] + (y1 * pyr.width + x0) * pyr.floats[b]);
    }
  }
  g.t = move ? s.te : g.t;
  g.nt = move ? s.ne : g.nt;
  g.bt = move ? s.be : g.bt;
  // Ray::left_levels(): a side at b bounds the cells of every level m with
  // 2^m dividing b, bits b ^ (b - 1).
  const VU left = ((s.movex & (s.vx == s.te)) ? reinterpret_cast<VU>(s.bx ^ (s.bx - 1)) : VU{}) |
                  ((s.movey & (s.vy == s.te)) ? reinterpret_cast<VU>(s.by ^ (s.by - 1)) : VU{});
  g.known = move ? g.known & ~left : g.known;
  // Empty so far: a bigger stride, unless still inside a cell above that
  // is known to overlap.
  const VU above = (g.known >> reinterpret_cast<VU>((g.level + 1) & 31)) & 1u;
  g.level = (move & (g.level < top) & (above == 0u)) ? g.level + 1 : g.level;
  g.it -= run;
}

}  // namespace

void hiz_walk_avx2(const WalkPyramid& pyr, const WalkHost& host, int budget) {
  if (budget <= 0) {  // no step to take: every ray misses, as `start` answered
    WalkRay r;
    while (host.start(host.ctx, 0, r)) {
    }
    return;
  }
  // Two groups of eight lanes, their steps side by side: one group's step is
  // a chain that waits on its gathers, and the other's fills that wait.
  constexpr int G = kGroups;
  Lanes g[G] = {};
  for (int k = 0; k < G; ++k) {
    g[k].first = N * k;
    g[k].live = true;
  }
  bool open = true;  // the queue may have more rays
  Step st[G];
  for (;;) {
    bool any = false;
    for (int k = 0; k < G; ++k) {
      if (g[k].live) g[k].live = refill(g[k], host, budget, open, st[k].run);
      any |= g[k].live;
    }
    if (!any) break;
#pragma GCC unroll 2
    for (int k = 0; k < G; ++k)
      if (g[k].live) locate(g[k], pyr, st[k]);
    for (int k = 0; k < G; ++k)
      if (g[k].live) advance(g[k], pyr, host, st[k]);
  }
}

}  // namespace glint::cpu
