// The hiz march's reuse of rays (docs/hiz.md, "Reusing neighbours' rays"):
// with resolution <= 0.5 a trace walks every other pixel of every other row
// first, and a pixel of the second pass takes its traced neighbours' answer
// where they lie on its surface and their reports agree. This file decides
// that and lists, row by row, the pixels left to walk; march_hiz.cpp walks
// them. The G-buffer half of the test also runs eight pixels at a time
// (hiz_reuse_avx2.cpp), the same bytes.
#include <algorithm>
#include <cmath>
#include <vector>

#include "cpu/outline.h"
#include "cpu/ray.h"
#include "glint/material.h"
#include "glint/schema.h"
#include "hiz.h"
#include "hiz_base.h"

namespace glint::cpu {
namespace {

// The method's constants, and why each has its value: glint/schema.h.
constexpr float kReusePixels = hiz::kReusePixels;
constexpr float kReuseSpanPixels = hiz::kReuseSpanPixels;
constexpr float kReuseSpanVisibility = hiz::kReuseSpanVisibility;

// What a report with visibility > 0 is: a hit (its own visibility in the
// fourth channel), an occluder found late (0) or a hidden side entered
// (kEnteredHidden). Neighbours of different kinds straddle an object's edge
// or the line where its hidden side begins: a pixel between them traces its
// own ray rather than take a mean uv that is neither, at the least weight of
// either.
inline int report_kind(const float* o) { return o[3] > 0.0f ? 1 : (o[3] == 0.0f ? 0 : -1); }

// Whether the texel under uv b lies on the plane of the texel under uv a:
// both seen, normals within kReuseCos, b off a's plane by at most
// kReuseDepth of a's view distance. In two steps, since one a is held
// against up to four b: plane_at() takes a's texel, on_plane_of() each b.
struct PlaneAt {
  const float *p = nullptr, *n = nullptr;
  float limit = 0.0f;  // the distance off the plane allowed, times |n|
};
bool plane_at(const TraceInputs& in, const float* a, PlaneAt& pl) {
  const Image& pos = in.position;
  int i = 0, j = 0;
  if (!pos.texel_at(a[0] * static_cast<float>(pos.width), a[1] * static_cast<float>(pos.height), i, j)) return false;
  pl.p = pos.px(i, j);
  if (!texel_seen(pl.p)) return false;
  pl.n = in.normal.px(i, j);
  const float* n = pl.n;
  pl.limit = hiz::kReuseDepth * std::fabs(pl.p[2]) * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  return true;
}
bool on_plane_of(const TraceInputs& in, const PlaneAt& pl, const float* b) {
  const Image& pos = in.position;
  int i = 0, j = 0;
  if (!pos.texel_at(b[0] * static_cast<float>(pos.width), b[1] * static_cast<float>(pos.height), i, j)) return false;
  const float* pb = pos.px(i, j);
  if (!texel_seen(pb)) return false;
  const float *pa = pl.p, *na = pl.n;
  if (!normals_agree(na, in.normal.px(i, j))) return false;
  const float g = na[0] * (pb[0] - pa[0]) + na[1] * (pb[1] - pa[1]) + na[2] * (pb[2] - pa[2]);
  return std::fabs(g) <= pl.limit;
}

// The traced pixels that pixel (x, y) of the second pass reads, into q: the
// two beside it (an even row), the two above and below (an odd row, even
// column), or the four at its corners. Returns how many.
int reuse_neighbours_of(int x, int y, int q[4][2]) {
  if (!(y & 1)) {
    q[0][0] = x - 1, q[0][1] = y, q[1][0] = x + 1, q[1][1] = y;
    return 2;
  }
  if (!(x & 1)) {
    q[0][0] = x, q[0][1] = y - 1, q[1][0] = x, q[1][1] = y + 1;
    return 2;
  }
  q[0][0] = x - 1, q[0][1] = y - 1, q[1][0] = x + 1, q[1][1] = y - 1;
  q[2][0] = x - 1, q[2][1] = y + 1, q[3][0] = x + 1, q[3][1] = y + 1;
  return 4;
}

// Whether the traced neighbours of pixel (x, y) (reuse_neighbours_of()) say
// what its own ray would find (docs/hiz.md, "Reusing neighbours' rays").
// It takes two halves: reuse_surface() reads only the G-buffer, so a row's
// answers can be had in one sweep (eight pixels at a time on AVX2), and
// reuse_reports() reads the first pass's reports for the pixels that pass.
//
// reuse_surface(): each neighbour lies on the image and on the pixel's smooth
// surface (reflective, normals within kReuseCos, view distances within
// kReuseDepth of each other: same_surface()). False also where the pixel
// itself is not reflective or has no ray: its own trace writes its 0 then.
bool reuse_surface(const TraceInputs& in, int x, int y) {
  if (in.specular && !is_reflective(in.specular->px(x, y))) return false;
  const float* p = in.position.px(x, y);
  const float* n = in.normal.px(x, y);
  // Only where the pixel's own ray exists (read_origin() would take it).
  if (!texel_seen(p) || !finite(V3{p[0], p[1], p[2]}) || !finite(V3{n[0], n[1], n[2]})) return false;
  int q[4][2];
  const int k = reuse_neighbours_of(x, y, q);
  for (int e = 0; e < k; ++e) {
    const int qx = q[e][0], qy = q[e][1];
    if (qx < 0 || qy < 0 || qx >= in.position.width || qy >= in.position.height) return false;
    if (!same_surface(in, p, n, qx, qy)) return false;
  }
  return true;
}

// reuse_reports(), for a pixel whose neighbours passed reuse_surface(): they
// either all missed or all hit within kReusePixels of each other, or all hit
// (real hits, not occluders) within kReuseSpanPixels on one plane
// (on_plane_of() from the first hit's texel to each other's and to their
// mean's) with visibilities within kReuseSpanVisibility. Then `o` is their
// miss, or their hits' mean uv with each channel's least visibility (with
// blocked=occluder an occluder, 0 in the 4th channel, counts as a hit) when
// they are of one kind (report_kind()); the mean visibility when they are on
// one plane further apart.
bool reuse_reports(const TraceInputs& in, const Image& out, int x, int y, float o[4]) {
  int q[4][2];
  const int k = reuse_neighbours_of(x, y, q);
  int hits = 0;
  for (int e = 0; e < k; ++e) hits += out.px(q[e][0], q[e][1])[2] > 0.0f;
  if (hits == 0) {
    o[0] = o[1] = o[2] = o[3] = 0.0f;
    return true;
  }
  if (hits < k) return false;
  const float w = static_cast<float>(out.width), h = static_cast<float>(out.height);
  const int kind = report_kind(out.px(q[0][0], q[0][1]));
  const float span = kind == 1 ? kReuseSpanPixels : kReusePixels;
  float su = 0.0f, sv = 0.0f, vis = 1.0f, found = 1.0f;
  float vis_sum = 0.0f, vis_max = 0.0f;
  bool wide = false;  // some hits are further apart than kReusePixels
  for (int a = 0; a < k; ++a) {
    const float* ha = out.px(q[a][0], q[a][1]);
    if (report_kind(ha) != kind) return false;
    for (int b = a + 1; b < k; ++b) {
      const float* hb = out.px(q[b][0], q[b][1]);
      const float du = (ha[0] - hb[0]) * w, dv = (ha[1] - hb[1]) * h;
      const float d2 = du * du + dv * dv;
      if (!(d2 <= span * span)) return false;
      wide |= !(d2 <= kReusePixels * kReusePixels);
    }
    su += ha[0];
    sv += ha[1];
    vis = std::min(vis, ha[2]);
    found = std::min(found, ha[3]);
    vis_sum += ha[2];
    vis_max = std::max(vis_max, ha[2]);
  }
  const float inv_k = 1.0f / static_cast<float>(k);
  const float mean[2] = {su * inv_k, sv * inv_k};
  if (wide) {
    if (!(vis_max - vis <= kReuseSpanVisibility)) return false;
    PlaneAt first;
    if (!plane_at(in, out.px(q[0][0], q[0][1]), first)) return false;
    for (int a = 1; a < k; ++a)
      if (!on_plane_of(in, first, out.px(q[a][0], q[a][1]))) return false;
    if (!on_plane_of(in, first, mean)) return false;
  }
  o[0] = mean[0];
  o[1] = mean[1];
  // On one plane a hit's visibility (edge fade times outline confidence)
  // varies smoothly, so the mean is the pixel's own ray's; the least, over
  // hits this far apart, would dim the screen's edge early. A hit's fourth
  // channel is its visibility.
  o[2] = wide ? vis_sum * inv_k : vis;
  o[3] = wide ? o[2] : found;
  return true;
}

}  // namespace

void hiz_row_jobs(const TraceInputs& in, Image& out, int y, int x0, int step, const unsigned char* reusable,
                  std::vector<int>& xs) {
  xs.clear();
  for (int x = x0; x < out.width; x += step) {
    float* o = out.px(x, y);
    if (reusable && reusable[x] && reuse_reports(in, out, x, y, o)) continue;
    o[0] = o[1] = o[2] = o[3] = 0.0f;
    if (in.specular && !is_reflective(in.specular->px(x, y))) continue;
    xs.push_back(x);
  }
}

// The AVX2 rows take the row's texels but its first and last, the row's ends
// go one at a time.
void hiz_reuse_surface_row(const TraceInputs& in, int y, WalkIsa isa, unsigned char* ok) {
  const int w = in.position.width, h = in.position.height;
  int x0 = 0, x1 = 0;  // [x0, x1): done eight at a time
#if defined(GLINT_WALK_AVX2)
  if (isa == WalkIsa::Avx2 && w >= 10 && (!(y & 1) || y + 1 < h)) {
    ReuseRow r;
    for (int k = 0; k < 3; ++k) {
      const int row = y - 1 + k;
      if (row < 0 || row >= h) continue;
      r.position[k] = in.position.px(0, row);
      r.normal[k] = in.normal.px(0, row);
      r.specular[k] = in.specular ? in.specular->px(0, row) : nullptr;
    }
    r.y = y;
    r.depth_share = hiz::kReuseDepth;
    r.cos2 = hiz::kReuseCos * hiz::kReuseCos;
    r.out = ok;
    x0 = 1;
    x1 = 1 + (w - 2) / 8 * 8;
    hiz_reuse_row_avx2(r, x0, x1);
  }
#else
  (void)isa;
#endif
  auto one = [&](int x) { ok[x] = (y & 1) || (x & 1) ? reuse_surface(in, x, y) : 0; };
  for (int x = 0; x < x0; ++x) one(x);
  for (int x = x1; x < w; ++x) one(x);
}

}  // namespace glint::cpu
