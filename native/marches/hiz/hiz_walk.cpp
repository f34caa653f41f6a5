// The hiz walk one ray at a time, the form every machine runs, and the choice
// of walk at run time (hiz_walk.h). hiz_walk_avx2.cpp runs the same steps on
// sixteen rays at once; hiz_walk.glsl is this function's port to GL.
#include <algorithm>
#include <cmath>
#include <limits>

#include "hiz_walk.h"

namespace glint::cpu {
namespace {

// Where the line leaves a cell whose sides on its way are bx (x) and by (y),
// as a fraction: a product per side by the inverse of its extent, in the one
// order the kernels and the shaders use. vx, vy: each side's own fraction.
inline float exit_at(const WalkRay& r, int bx, int by, float& vx, float& vy) {
  float te = r.t_end;
  vx = (static_cast<float>(bx) - r.f0[0]) * r.inv[0];
  vy = (static_cast<float>(by) - r.f0[1]) * r.inv[1];
  if (r.d[0] != 0.0f) te = std::min(te, vx);
  if (r.d[1] != 0.0f) te = std::min(te, vy);
  return te;
}

}  // namespace

void hiz_walk_scalar(const WalkPyramid& pyr, const WalkHost& host, int budget) {
  const int top = pyr.levels - 1;
  float scale[32];  // 1 / 2^level: pixels to cells, exactly
  for (int l = 0; l < 32; ++l) scale[l] = std::ldexp(1.0f, -l);
  WalkRay r;
  while (host.start(host.ctx, 0, r)) {
    float t = r.t, nt = r.nt, bt = r.bt;
    int level = 0;
    // Bit l of `known`: the cell of level l that the ray is in is known to
    // overlap it (it was the reason to go down a level). While the ray is
    // still inside such a cell, passing a cell below it is no reason to go
    // back up: the cell above would be tested again over what is left of the
    // same span and overlap again, most of the time (a ray skimming a floor
    // went up and straight back down on 7 of its 27 steps). Which texels are
    // tested does not change, only the steps to reach them, so fewer rays run
    // out of their budget. A mask, not the cells' exits: the GL walk pays
    // dearly for an array indexed by level.
    unsigned known = 0;
    for (int it = 0; it < budget && t < r.t_end; ++it) {
      // The cell of `level` the line occupies just past t: kCellNudge
      // (march_hiz.cpp) along its direction. Truncation is floor for the
      // non-negative values that reach it; the last cell where the line is at
      // or past the far side, the first where it is not past 0 (or not a
      // number).
      const float px = r.f0[0] + t * r.d[0] + r.nudge[0], py = r.f0[1] + t * r.d[1] + r.nudge[1];
      const float sx = px * scale[level], sy = py * scale[level];
      const int wl = std::max(1, pyr.width >> level), hl = std::max(1, pyr.height >> level);
      const int i = !(sx > 0.0f) ? 0 : (sx >= static_cast<float>(wl) ? wl - 1 : static_cast<int>(sx));
      const int j = !(sy > 0.0f) ? 0 : (sy >= static_cast<float>(hl) ? hl - 1 : static_cast<int>(sy));
      // The cell's sides on the ray's way (the last cell of a row or column
      // also covers what an odd size leaves over), and where it leaves it.
      const int bx = r.d[0] > 0.0f ? (i == wl - 1 ? pyr.width : (i + 1) << level) : i << level;
      const int by = r.d[1] > 0.0f ? (j == hl - 1 ? pyr.height : (j + 1) << level) : j << level;
      float vx, vy;
      float te = exit_at(r, bx, by, vx, vy);
      if (!(te > t)) te = std::nextafter(t, std::numeric_limits<float>::infinity());  // always move on
      const float ne = -(r.a0z + te * r.daz), be = r.b0 + te * r.db;
      const float* c = pyr.range + 2 * (static_cast<size_t>(pyr.offset[level]) + static_cast<size_t>(j) * wl + i);
      // The depth span [min, max] of the two ends meets [c0, c1]; the walk
      // compares num with range * b and never divides (b > 0).
      if ((nt >= c[0] * bt || ne >= c[0] * be) && (nt <= c[1] * bt || ne <= c[1] * be)) {
        if (level > 0) {
          known |= 1u << level;
          --level;  // something in this cell may meet the ray: look closer
          if (level == 0) {
            // What a texel test reads next, from far in memory: both rows of
            // this cell's texels. Loads only.
            const long x0 = std::min(2 * i, pyr.width - 1), y0 = std::min(2 * j, pyr.height - 1);
            const long y1 = std::min<long>(y0 + 1, pyr.height - 1);
            for (int b = 0; b < 2; ++b) {
              __builtin_prefetch(pyr.texel[b] + (y0 * pyr.width + x0) * pyr.floats[b]);
              __builtin_prefetch(pyr.texel[b] + (y1 * pyr.width + x0) * pyr.floats[b]);
            }
          }
          continue;
        }
        if (!host.texel(host.ctx, 0, i, j, t, te)) break;  // the ray ended at this texel
      }
      t = te;
      nt = ne;
      bt = be;
      // The levels whose cell the line left at te: a side at pixel coordinate
      // b bounds the cells of every level m with 2^m dividing b (0: the
      // image's edge, all of them), and b ^ (b - 1) has bits 0..ctz(b) set.
      unsigned left = 0;
      if (r.d[0] != 0.0f && vx == te) left |= static_cast<unsigned>(bx ^ (bx - 1));
      if (r.d[1] != 0.0f && vy == te) left |= static_cast<unsigned>(by ^ (by - 1));
      known &= ~left;
      // Empty so far: try a bigger stride, unless still inside a cell above
      // that is known to overlap.
      if (level < top && !((known >> (level + 1)) & 1u)) ++level;
    }
  }
}

bool hiz_walk_available(WalkIsa isa) {
  switch (isa) {
    case WalkIsa::Scalar:
      return true;
    case WalkIsa::Avx2:
#if defined(GLINT_WALK_AVX2)
      // libgcc's answer also checks that the OS saves the ymm registers.
      return __builtin_cpu_supports("avx2");
#else
      return false;
#endif
  }
  return false;
}

WalkIsa hiz_walk_default() {
  static const WalkIsa best = hiz_walk_available(WalkIsa::Avx2) ? WalkIsa::Avx2 : WalkIsa::Scalar;
  return best;
}

void hiz_walk(const WalkPyramid& pyr, const WalkHost& host, int budget, WalkIsa isa) {
#if defined(GLINT_WALK_AVX2)
  if (isa == WalkIsa::Avx2) return hiz_walk_avx2(pyr, host, budget);
#endif
  (void)isa;
  hiz_walk_scalar(pyr, host, budget);
}

void hiz_walk(const WalkPyramid& pyr, const WalkHost& host, int budget) {
  hiz_walk(pyr, host, budget, hiz_walk_default());
}

}  // namespace glint::cpu
