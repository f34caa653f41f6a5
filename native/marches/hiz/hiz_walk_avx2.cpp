// The hiz walk (hiz_walk.h) for x86-64 CPUs with AVX2: eight rays at once,
// one per lane of a ymm register. This file alone is built with -mavx2, and
// hiz_walk.cpp calls it only where the CPU has AVX2. Not -mfma: contracted
// products would round differently from the scalar walk and the shaders. It
// includes nothing with inline functions of its own and keeps its helpers in
// an anonymous namespace, so that the linker is never handed an AVX2 copy of
// a function the rest of the library calls on a machine without AVX2.
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
#include <immintrin.h>

#include "hiz_walk.h"

#if !defined(__AVX2__)
#error "hiz_walk_avx2.cpp is built with -mavx2"
#endif

namespace glint::cpu {
namespace {

constexpr int N = 8;  // one ymm register per vector
static_assert(N <= kWalkLanes, "the caller keeps kWalkLanes rays");
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

}  // namespace

void hiz_walk_avx2(const WalkPyramid& pyr, const WalkHost& host, int budget) {
  if (budget <= 0) {  // no step to take: every ray misses, as `start` answered
    WalkRay r;
    while (host.start(host.ctx, 0, r)) {
    }
    return;
  }
  const VI zero = {};
  const VF fzero = {};
  // The rays, a lane each; lanes without a ray keep level 0 and t 0, so
  // that their cells (computed and ignored) stay inside the pyramid.
  VF f0x = fzero, f0y = fzero, dx = fzero, dy = fzero, ix = fzero, iy = fzero, nx = fzero, ny = fzero;
  VF a0z = fzero, daz = fzero, b0 = fzero, db = fzero, t_end = fzero;
  VF t = fzero, nt = fzero, bt = fzero;
  VI level = zero, it = zero, alive = zero;
  VU known = {};
  const VI width = zero + pyr.width, height = zero + pyr.height;
  const int top = pyr.levels - 1;
  bool open = true;  // the queue may have more rays

  for (;;) {
    VI run = alive & (it < budget) & (t < t_end);
    if (lane_bits(run) != kAllLanes) {
      // Rays out of steps or past the screen's edge end here (their answer
      // is the miss already written); empty lanes take the next rays.
      alive = run;
      if (open) {
        unsigned empty = ~lane_bits(alive) & kAllLanes;
        while (empty && open) {
          const int k = __builtin_ctz(empty);
          WalkRay r;
          if (!host.start(host.ctx, k, r)) {
            open = false;
            break;
          }
          if (!(r.t < r.t_end)) continue;  // left the screen with its own texel
          f0x[k] = r.f0[0];
          f0y[k] = r.f0[1];
          dx[k] = r.d[0];
          dy[k] = r.d[1];
          ix[k] = r.inv[0];
          iy[k] = r.inv[1];
          nx[k] = r.nudge[0];
          ny[k] = r.nudge[1];
          a0z[k] = r.a0z;
          daz[k] = r.daz;
          b0[k] = r.b0;
          db[k] = r.db;
          t_end[k] = r.t_end;
          t[k] = r.t;
          nt[k] = r.nt;
          bt[k] = r.bt;
          level[k] = 0;
          known[k] = 0;
          it[k] = 0;
          alive[k] = -1;
          empty &= empty - 1;
        }
      }
      run = alive;
      if (!lane_bits(run)) break;  // no ray left
    }

    // The cell each lane's ray is in just past t (as hiz_walk_scalar(), with
    // its two branches as a clamp: the first cell where the line is not past
    // 0 or not a number, the last where it is at or past the far side).
    const VF px = f0x + t * dx + nx, py = f0y + t * dy + ny;
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
    const VI bx = dx > 0.0f ? (i == wl - 1 ? width : (i + 1) << level) : i << level;
    const VI by = dy > 0.0f ? (j == hl - 1 ? height : (j + 1) << level) : j << level;
    const VF vx = (__builtin_convertvector(bx, VF) - f0x) * ix;
    const VF vy = (__builtin_convertvector(by, VF) - f0y) * iy;
    const VI movex = dx != 0.0f, movey = dy != 0.0f;
    VF te = t_end;
    te = (movex & (vx < te)) ? vx : te;
    te = (movey & (vy < te)) ? vy : te;
    te = te > t ? te : next_up(t);  // always move on
    const VF ne = -(a0z + te * daz), be = b0 + te * db;
    VF c0, c1;
    cell_range(pyr.range, level_offset(pyr.offset, level) + j * wl + i, c0, c1);
    // The depth span [min, max] of the two ends meets [c0, c1].
    const VI overlap = ((nt >= c0 * bt) | (ne >= c0 * be)) & ((nt <= c1 * bt) | (ne <= c1 * be));

    // Level-0 texels the span meets: the caller's plane test, lane by lane.
    VI pass = zero;
    for (unsigned test = lane_bits(run & overlap & (level == 0)); test; test &= test - 1) {
      const int k = __builtin_ctz(test);
      if (host.texel(host.ctx, k, i[k], j[k], t[k], te[k]))
        pass[k] = -1;
      else
        alive[k] = 0;
    }

    const VI down = run & overlap & (level > 0);
    const VI move = run & (~overlap | pass);
    known = down ? known | (VU{} + 1u) << reinterpret_cast<VU>(level) : known;
    level = down ? level - 1 : level;
    for (unsigned m = lane_bits(down & (level == 0)); m; m &= m - 1) {
      const int k = __builtin_ctz(m);
      const long x0 = 2 * i[k] < pyr.width ? 2 * i[k] : pyr.width - 1;
      const long y0 = 2 * j[k] < pyr.height ? 2 * j[k] : pyr.height - 1;
      const long y1 = y0 + 1 < pyr.height ? y0 + 1 : y0;
      for (int b = 0; b < 2; ++b) {
        __builtin_prefetch(pyr.texel[b] + (y0 * pyr.width + x0) * pyr.floats[b]);
        __builtin_prefetch(pyr.texel[b] + (y1 * pyr.width + x0) * pyr.floats[b]);
      }
    }
    t = move ? te : t;
    nt = move ? ne : nt;
    bt = move ? be : bt;
    // Ray::left_levels(): a side at b bounds the cells of every level m with
    // 2^m dividing b, bits b ^ (b - 1).
    const VU left = ((movex & (vx == te)) ? reinterpret_cast<VU>(bx ^ (bx - 1)) : VU{}) |
                    ((movey & (vy == te)) ? reinterpret_cast<VU>(by ^ (by - 1)) : VU{});
    known = move ? known & ~left : known;
    // Empty so far: a bigger stride, unless still inside a cell above that
    // is known to overlap.
    const VU above = (known >> reinterpret_cast<VU>((level + 1) & 31)) & 1u;
    level = (move & (level < top) & (above == 0u)) ? level + 1 : level;
    it -= run;
  }
}

}  // namespace glint::cpu
