// Antialiased outlines: finding the pixels and resolving their rays (outline.h).
#include "outline.h"

#include <cmath>

#include "glint/material.h"
#include "parallel.h"
#include "ray.h"

namespace glint::cpu {
namespace {

// Pixel (x, y) is on a reflection's outline when its report is a hit and a
// neighbour's on the same surface a miss, or the other way round, and the
// pixel's reflection is sharp there: where the cone blur's footprint at the
// hit spans more than a pixel (cone_lod_at() > 0), the blur already spreads
// the edge over it, and rays inside the pixel would buy nothing.
// `reports` holds report_of() of every pixel, a byte each. They are compared
// first: most pixels agree with all four neighbours, and the G-buffer is then
// never read.
bool on_outline(const TraceInputs& in, const Image& out, const unsigned char* reports, int x, int y) {
  const int width = out.width, height = out.height;
  const auto report = [&](int i, int j) { return static_cast<Report>(reports[static_cast<size_t>(j) * width + i]); };
  const Report r = report(x, y);
  if (r == Report::Other) return false;
  const int nb[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
  bool differs[4] = {false, false, false, false};
  bool any = false;
  for (int k = 0; k < 4; ++k) {
    const int* q = nb[k];
    if (q[0] < 0 || q[1] < 0 || q[0] >= width || q[1] >= height) continue;
    const Report rq = report(q[0], q[1]);
    any |= differs[k] = rq != Report::Other && rq != r;
  }
  if (!any) return false;
  if (in.specular && !is_reflective(in.specular->px(x, y))) return false;
  const float* p = in.position.px(x, y);
  const float* n = in.normal.px(x, y);
  if (!texel_seen(p) || !finite(V3{p[0], p[1], p[2]}) || !finite(V3{n[0], n[1], n[2]})) return false;
  const float* spec = in.specular ? in.specular->px(x, y) : nullptr;
  for (int k = 0; k < 4; ++k) {
    if (!differs[k] || !same_surface(in, p, n, nb[k][0], nb[k][1])) continue;
    const float* hit = r == Report::Hit ? out.px(x, y) : out.px(nb[k][0], nb[k][1]);
    if (!spec || !(cone_lod_at(x, y, width, height, hit, spec) > 0.0f)) return true;
  }
  return false;
}

}  // namespace

bool same_surface(const TraceInputs& in, const float* p, const float* n, int qx, int qy) {
  if (in.specular && !is_reflective(in.specular->px(qx, qy))) return false;
  const float* pq = in.position.px(qx, qy);
  const float* nq = in.normal.px(qx, qy);
  if (!texel_seen(pq) || !(std::fabs(pq[2] - p[2]) <= hiz::kReuseDepth * std::fabs(p[2]))) return false;
  return normals_agree(n, nq);
}

std::vector<std::vector<int>> outline_pixels(const TraceInputs& in, const Image& out, int threads) {
  const int width = out.width, height = out.height;
  std::vector<unsigned char> reports(out.pixel_count());
  parallel_rows(0, height, threads, [&](int y) {
    unsigned char* row = reports.data() + static_cast<size_t>(y) * width;
    for (int x = 0; x < width; ++x) row[x] = static_cast<unsigned char>(report_of(out.px(x, y)));
  });
  // A hit beside a miss is on_outline()'s first test: with Miss 0 and Hit 1,
  // the neighbour to look for is report ^ 1 (Other's 3 matches nothing). Done
  // on whole rows in byte lanes, so that the nine pixels in ten nowhere near
  // an outline cost a few instructions; rows past the image are all Other.
  static_assert(static_cast<int>(Report::Miss) == 0 && static_cast<int>(Report::Hit) == 1 &&
                static_cast<int>(Report::Other) == 2, "the byte test below");
  const std::vector<unsigned char> none(static_cast<size_t>(width), static_cast<unsigned char>(Report::Other));
  std::vector<std::vector<int>> edges(static_cast<size_t>(height));
  parallel_rows(0, height, threads, [&](int y) {
    const unsigned char* r = reports.data() + static_cast<size_t>(y) * width;
    const unsigned char* up = y + 1 < height ? r + width : none.data();
    const unsigned char* down = y > 0 ? r - width : none.data();
    std::vector<unsigned char> near(static_cast<size_t>(width));
    const auto test = [&](int x, unsigned char left, unsigned char right) {
      const unsigned char m = r[x] ^ 1;
      return static_cast<unsigned char>((left == m) | (right == m) | (up[x] == m) | (down[x] == m));
    };
    near[0] = test(0, 2, width > 1 ? r[1] : 2);
    for (int x = 1; x + 1 < width; ++x) near[x] = test(x, r[x - 1], r[x + 1]);
    if (width > 1) near[width - 1] = test(width - 1, r[width - 2], 2);
    for (int x = 0; x < width; ++x)
      if (near[x] && on_outline(in, out, reports.data(), x, y)) edges[y].push_back(x);
  });
  return edges;
}

void resolve_outline(const float* c, const float* samples, int k, float w, float h, float* o) {
  const float* ref = c[3] > 0.0f ? c : nullptr;
  for (int j = 0; j < k && !ref; ++j)
    if (samples[4 * j + 3] > 0.0f) ref = samples + 4 * j;
  if (!ref) return;
  float su = 0.0f, sv = 0.0f, sw = 0.0f;
  // Every read happens before the first write: `o` may be `c`.
  auto add = [&](const float* s) {
    const Report r = report_of(s);
    if (r != Report::Hit) return r == Report::Miss;
    const float du = (s[0] - ref[0]) * w, dv = (s[1] - ref[1]) * h;
    if (!(du * du + dv * dv <= hiz::kReusePixels * hiz::kReusePixels)) return false;
    su += s[3] * s[0];
    sv += s[3] * s[1];
    sw += s[3];
    return true;
  };
  if (!add(c)) return;
  for (int j = 0; j < k; ++j)
    if (!add(samples + 4 * j)) return;
  const float vis = sw / static_cast<float>(k + 1);
  o[0] = su / sw;
  o[1] = sv / sw;
  o[2] = o[3] = vis;
}

}  // namespace glint::cpu
