// composite_layers() and continue_missing_uv(): the per-frame images of a
// compositor outside the core (glint/composite.h).
#include "glint/composite.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "glint/brdf.h"
#include "glint/errors.h"
#include "glint/material.h"
#include "glint/projection.h"
#include "glint/validation.h"
#include "parallel.h"

namespace glint {

namespace {

// Pooled (glint/image.h): a frame's masks come back already mapped.
using Mask = std::vector<unsigned char, PixelAllocator<unsigned char>>;

// A float sum in numpy's add.reduceat order, along either axis: the first
// term plus (0 + second + third ...), its pairwise sum, which is sequential
// below 8 terms.
struct ReduceatSum {
  float first = 0.0f, rest = 0.0f;
  int terms = 0;
  void add(float v) {
    if (terms++ == 0)
      first = v;
    else
      rest += v;
  }
  float value() const { return terms > 1 ? first + rest : first; }
};

// A hit's visibility under this share of its screen-edge fade is one its
// march was unsure of (an outline texel's confidence), not rounding.
constexpr float kSettledShare = 0.999f;

// No pixel in [x, x + 8) of row y has a known 3x3 neighbour: the ten bytes
// x - 1 .. x + 8 of rows y - 1 .. y + 1 are all zero. Needs 1 <= x, x + 9 <= w.
inline bool none_near8(const unsigned char* m, int w, int h, int x, int y) {
  uint64_t any = 0;
  for (int yy = std::max(0, y - 1); yy <= std::min(h - 1, y + 1); ++yy) {
    const unsigned char* row = m + static_cast<size_t>(yy) * w;
    uint64_t a, b;
    std::memcpy(&a, row + x - 1, 8);
    std::memcpy(&b, row + x + 1, 8);
    any |= a | b;
  }
  return any == 0;
}

}  // namespace

void continue_missing_uv(Image& uv, int rings, int threads) {
  const int w = uv.width, h = uv.height;
  Mask known(uv.pixel_count()), before(uv.pixel_count());
  parallel_rows(0, h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) known[static_cast<size_t>(y) * w + x] = uv.px(x, y)[2] > 0.0f;
  });
  for (int ring = 0; ring < rings; ++ring) {
    before = known;
    // A ring pixel reads only pixels known before this ring, which no one
    // writes during it: rows can run in any order.
    std::atomic<bool> grew{false};
    parallel_rows(0, h, threads, [&](int y) {
      bool any = false;
      for (int x = 0; x < w; ++x) {
        // Most of a frame is far from any hit: skip it eight pixels at a time.
        if (x >= 1 && x + 9 <= w && none_near8(before.data(), w, h, x, y)) {
          x += 7;
          continue;
        }
        if (before[static_cast<size_t>(y) * w + x]) continue;
        float acc[2] = {0.0f, 0.0f}, count = 0.0f;
        for (int dy = -1; dy <= 1; ++dy) {
          const int yy = y + dy;
          if (yy < 0 || yy >= h) continue;
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx;
            if (xx < 0 || xx >= w || !before[static_cast<size_t>(yy) * w + xx]) continue;
            const float* q = uv.px(xx, yy);
            acc[0] += q[0];
            acc[1] += q[1];
            count += 1.0f;
          }
        }
        if (count == 0.0f) continue;
        float* o = uv.px(x, y);
        o[0] = acc[0] / count;
        o[1] = acc[1] / count;
        known[static_cast<size_t>(y) * w + x] = 1;
        any = true;
      }
      if (any) grew.store(true, std::memory_order_relaxed);
    });
    if (!grew.load()) break;
  }
}

void continue_lod_into_misses(Image& weight, const Image& uv, const Image& specular, const Image& position,
                              int threads) {
  const int w = uv.width, h = uv.height;
  auto hit = [&](int x, int y) { return uv.px(x, y)[2] > 0.0f; };
  // Only the box the hits' footprints can reach is walked: a frame's misses
  // far from any blurred hit cost nothing. The hits' box and largest lod, a
  // row at a time on the workers.
  struct Row {
    int x0, x1;
    float top;
  };
  std::vector<Row> rows(static_cast<size_t>(h));
  parallel_rows(0, h, threads, [&](int y) {
    Row r{w, -1, 0.0f};
    for (int x = 0; x < w; ++x) {
      if (!hit(x, y)) continue;
      r.x0 = std::min(r.x0, x), r.x1 = std::max(r.x1, x);
      r.top = std::max(r.top, weight.px(x, y)[3]);
    }
    rows[static_cast<size_t>(y)] = r;
  });
  int x0 = w, y0 = h, x1 = -1, y1 = -1;
  float top = 0.0f;
  for (int y = 0; y < h; ++y) {
    const Row& r = rows[static_cast<size_t>(y)];
    if (r.x1 < 0) continue;
    x0 = std::min(x0, r.x0), x1 = std::max(x1, r.x1), y0 = std::min(y0, y), y1 = std::max(y1, y);
    top = std::max(top, r.top);
  }
  if (x1 < 0 || !(top > 0.0f)) return;
  // Any lod past the image's size reaches the whole image (and an infinite
  // one from an outside caller must not overflow the cast).
  const float far = std::exp2(top - 1.0f) * kChamferSlack;
  const int reach = far < static_cast<float>(std::max(w, h)) ? static_cast<int>(std::ceil(far)) : std::max(w, h);
  x0 = std::max(0, x0 - reach), y0 = std::max(0, y0 - reach);
  x1 = std::min(w - 1, x1 + reach), y1 = std::min(h - 1, y1 + reach);
  const int bw = x1 - x0 + 1, bh = y1 - y0 + 1;
  // The distance to the nearest hit; the lod that hit has travels in the
  // weight's own alpha (a miss's is overwritten), so the walk needs one float
  // a pixel of the box beside the images (130 MB at 8K, not 260).
  std::vector<float, PixelAllocator<float>> dist(static_cast<size_t>(bw) * bh);
  const float inf = std::numeric_limits<float>::infinity();
  parallel_rows(y0, y1 + 1, threads, [&](int y) {
    float* d = dist.data() + static_cast<size_t>(y - y0) * bw;
    for (int x = x0; x <= x1; ++x) {
      const bool h0 = hit(x, y);
      d[x - x0] = h0 ? 0.0f : inf;
      if (!h0) weight.px(x, y)[3] = 0.0f;
    }
  });
  // Two raster passes of the 3x3 chamfer distance (steps 1 and sqrt 2), each
  // pixel keeping the lod of the hit it is nearest to: one thread, in order.
  // Box coordinates from here; a neighbour is an offset in each array, and
  // the box's edges are checked only on its edge pixels.
  const float diag = 1.41421356f;
  // Box pixel (x, y)'s distance at dist[y * bw + x], its lod at lod[(y * w + x) * 4].
  float* lod = weight.px(x0, y0) + 3;
  const size_t row = static_cast<size_t>(bw), lod_row = static_cast<size_t>(w) * 4;
  auto relax = [&](size_t i, size_t li, ptrdiff_t dj, ptrdiff_t dl, float step) {
    if (dist[i + dj] + step < dist[i]) dist[i] = dist[i + dj] + step, lod[li] = lod[li + dl];
  };
  auto relax_at = [&](int x, int y, int dx, int dy, float step) {
    const int nx = x + dx, ny = y + dy;
    if (nx < 0 || nx >= bw || ny < 0 || ny >= bh) return;
    relax(static_cast<size_t>(y) * row + x, static_cast<size_t>(y) * lod_row + 4 * static_cast<size_t>(x),
          dy * static_cast<ptrdiff_t>(row) + dx, dy * static_cast<ptrdiff_t>(lod_row) + 4 * dx, step);
  };
  const ptrdiff_t r = static_cast<ptrdiff_t>(row), lr = static_cast<ptrdiff_t>(lod_row);
  for (int y = 0; y < bh; ++y)
    for (int x = 0; x < bw; ++x) {
      const size_t i = static_cast<size_t>(y) * row + x;
      const size_t li = static_cast<size_t>(y) * lod_row + 4 * static_cast<size_t>(x);
      if (dist[i] == 0.0f) continue;  // a hit: nothing is nearer
      if (y > 0 && x > 0 && x + 1 < bw) {
        relax(i, li, -1, -4, 1.0f), relax(i, li, -r - 1, -lr - 4, diag), relax(i, li, -r, -lr, 1.0f),
            relax(i, li, -r + 1, -lr + 4, diag);
      } else {
        relax_at(x, y, -1, 0, 1.0f), relax_at(x, y, -1, -1, diag);
        relax_at(x, y, 0, -1, 1.0f), relax_at(x, y, 1, -1, diag);
      }
    }
  for (int y = bh - 1; y >= 0; --y)
    for (int x = bw - 1; x >= 0; --x) {
      const size_t i = static_cast<size_t>(y) * row + x;
      const size_t li = static_cast<size_t>(y) * lod_row + 4 * static_cast<size_t>(x);
      if (dist[i] == 0.0f) continue;
      if (y + 1 < bh && x > 0 && x + 1 < bw) {
        relax(i, li, 1, 4, 1.0f), relax(i, li, r + 1, lr + 4, diag), relax(i, li, r, lr, 1.0f),
            relax(i, li, r - 1, lr - 4, diag);
      } else {
        relax_at(x, y, 1, 0, 1.0f), relax_at(x, y, 1, 1, diag);
        relax_at(x, y, 0, 1, 1.0f), relax_at(x, y, -1, 1, diag);
      }
    }
  parallel_rows(y0, y1 + 1, threads, [&](int y) {
    const float* d = dist.data() + static_cast<size_t>(y - y0) * bw;
    for (int x = x0; x <= x1; ++x) {
      if (hit(x, y)) continue;
      float& m = weight.px(x, y)[3];
      const bool keep = m > 0.0f && d[x - x0] <= std::exp2(m - 1.0f) * kChamferSlack &&
                        texel_seen(position.px(x, y)) && is_reflective(specular.px(x, y));
      if (!keep) m = 0.0f;
    }
  });
}

void read_inside_outlines(Image& uv, const Image& pos, const Image* back_position, float thickness, int threads) {
  require_same_size(pos, "position", uv, "uv");
  if (back_position) require_same_size(pos, "position", *back_position, "back_position");
  const int w = pos.width, h = pos.height;
  auto inside_frame = [&](int x, int y) { return x >= 0 && y >= 0 && x < w && y < h; };
  parallel_rows(0, h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      float* t = uv.px(x, y);
      int i = 0, j = 0;
      if (!(t[2] > 0.0f) || !pos.texel_at(t[0] * static_cast<float>(w), t[1] * static_cast<float>(h), i, j) ||
          !texel_seen(pos.px(i, j)))
        continue;
      // thickness >= 0: a NaN or negative option is refused before.
      auto bound_of = [&](int ax, int ay) {
        return -pos.px(ax, ay)[2] + texel_thickness(pos, back_position, thickness, ax, ay);
      };
      // Texel q lies outside the object whose depth plus thickness is `bound`:
      // unseen, or farther. The frame's edge is no outline.
      auto beyond = [&](float bound, int qx, int qy) {
        if (!inside_frame(qx, qy)) return false;
        const float* o = pos.px(qx, qy);
        return !texel_seen(o) || -o[2] > bound;
      };
      const float bound = bound_of(i, j);
      auto outside = [&](int qx, int qy) { return beyond(bound, qx, qy); };
      const int si = (outside(i - 1, j) ? 1 : 0) - (outside(i + 1, j) ? 1 : 0);
      const int sj = (outside(i, j - 1) ? 1 : 0) - (outside(i, j + 1) ? 1 : 0);
      if (si == 0 && sj == 0) {
        // Inside, but a read within half a texel of an outline texel takes in
        // some of it (and of what the frame blends into it) through the
        // sampler's footprint: such a read moves to its own texel's centre
        // along that axis. The texel beside counts as an outline when the one
        // beyond it, on the same line, lies outside it.
        auto rim = [&](int ax, int ay, int bx, int by) {
          if (!inside_frame(ax, ay)) return false;
          return outside(ax, ay) || beyond(bound_of(ax, ay), bx, by);
        };
        const float fx = t[0] * static_cast<float>(w) - static_cast<float>(i);
        const float fy = t[1] * static_cast<float>(h) - static_cast<float>(j);
        const int ex = fx < 0.5f ? -1 : 1, ey = fy < 0.5f ? -1 : 1;
        if (rim(i + ex, j, i + 2 * ex, j)) t[0] = (static_cast<float>(i) + 0.5f) / static_cast<float>(w);
        if (rim(i, j + ey, i, j + 2 * ey)) t[1] = (static_cast<float>(j) + 0.5f) / static_cast<float>(h);
        continue;
      }
      const int qi = i + si, qj = j + sj;
      if (!inside_frame(qi, qj) || !texel_seen(pos.px(qi, qj)) || outside(qi, qj)) continue;
      t[0] = (static_cast<float>(qi) + 0.5f) / static_cast<float>(w);
      t[1] = (static_cast<float>(qj) + 0.5f) / static_cast<float>(h);
    }
  });
}

Image hidden_sides(const Image& traced_uv, const Image& back_albedo, uint64_t& count, int threads) {
  if (back_albedo.width != traced_uv.width || back_albedo.height != traced_uv.height)
    throw InvalidArgument("back_albedo", "expected the trace's size " + std::to_string(traced_uv.width) + "x" +
                                             std::to_string(traced_uv.height) + ", got " +
                                             std::to_string(back_albedo.width) + "x" +
                                             std::to_string(back_albedo.height));
  const int w = traced_uv.width, h = traced_uv.height;
  Image out(w, h, 0.0f);
  std::atomic<uint64_t> total{0};
  parallel_rows(0, h, threads, [&](int y) {
    uint64_t n = 0;
    for (int x = 0; x < w; ++x) {
      const float* t = traced_uv.px(x, y);
      if (!(t[2] > 0.0f) || t[3] != hiz::kEnteredHidden) continue;  // a hit, an occluder, or nothing
      // The occluder's texel: blocked="occluder" reports its centre.
      int i = 0, j = 0;
      if (!traced_uv.texel_at(t[0] * static_cast<float>(w), t[1] * static_cast<float>(h), i, j)) continue;
      const float* a = back_albedo.px(i, j);
      if (!(a[3] > 0.0f)) continue;  // an open surface: nothing known behind it
      float* o = out.px(x, y);
      for (int c = 0; c < 3; ++c) o[c] = a[c];
      o[3] = t[2];
      ++n;
    }
    total.fetch_add(n, std::memory_order_relaxed);
  });
  count = total.load();
  return out;
}

uint64_t settle_uncertain_shares(Image& uv, Image& hidden, const Image& back_albedo, int threads) {
  const int w = uv.width, h = uv.height;
  if (hidden.width != w || hidden.height != h || back_albedo.width != w || back_albedo.height != h)
    throw InvalidArgument("hidden", "expected the trace's size " + std::to_string(w) + "x" + std::to_string(h));
  const float fw = static_cast<float>(w), fh = static_cast<float>(h);
  // Decided on the trace as it came, then applied: a pixel's neighbours are
  // read before any of them changes. ToHidden + 1 + k: the hidden side's
  // albedo is that of neighbour k's texel (kAround[k]), the one its ray
  // entered, where the hit's own texel has no back surface (a rim texel the
  // back layer does not cover). Those neighbours are never written.
  enum : unsigned char { Keep, ToHit, ToHidden };
  static constexpr int kAround[8][2] = {{-1, -1}, {0, -1}, {1, -1}, {-1, 0}, {1, 0}, {-1, 1}, {0, 1}, {1, 1}};
  const auto back_at = [&](const float* t, int& i, int& j) {
    return uv.texel_at(t[0] * fw, t[1] * fh, i, j) && back_albedo.px(i, j)[3] > 0.0f;
  };
  Mask action(uv.pixel_count());
  parallel_rows(0, h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const float* t = uv.px(x, y);
      unsigned char& a = action[static_cast<size_t>(y) * w + x];
      a = Keep;
      if (!(t[3] > 0.0f)) continue;  // only hits (an occluder, a hidden side or nothing: no)
      const float fade = hiz::pixel_edge_fade(x, y, w, h, t[0], t[1]);
      if (!(t[2] < fade * kSettledShare)) continue;  // sure of itself, to the rounding
      if (x == 0 || y == 0 || x == w - 1 || y == h - 1) continue;
      bool inside = true, beside_hidden = false;
      int entered_back = -1;  // the first entered neighbour whose texel has a back surface
      for (int k = 0; k < 8 && inside; ++k) {
        const float* q = uv.px(x + kAround[k][0], y + kAround[k][1]);
        const float du = (q[0] - t[0]) * fw, dv = (q[1] - t[1]) * fh;
        // A hidden side's report is the texel the ray entered, a few texels
        // behind the rim the pixel hit: any distance is the same object's.
        const bool entered = q[3] == hiz::kEnteredHidden;
        inside = q[2] > 0.0f && (entered || du * du + dv * dv <= hiz::kReusePixels * hiz::kReusePixels);
        beside_hidden = beside_hidden || entered;
        int i = 0, j = 0;
        if (entered && entered_back < 0 && back_at(q, i, j)) entered_back = k;
      }
      if (!inside) continue;
      int i = 0, j = 0;
      if (!beside_hidden) a = ToHit;
      else if (back_at(t, i, j)) a = ToHidden;
      else a = entered_back >= 0 ? static_cast<unsigned char>(ToHidden + 1 + entered_back) : ToHit;
    }
  });
  std::atomic<uint64_t> total{0};
  parallel_rows(0, h, threads, [&](int y) {
    uint64_t n = 0;
    for (int x = 0; x < w; ++x) {
      const unsigned char a = action[static_cast<size_t>(y) * w + x];
      if (a == Keep) continue;
      float* t = uv.px(x, y);
      const float fade = hiz::pixel_edge_fade(x, y, w, h, t[0], t[1]);
      if (a == ToHit) {
        t[2] = t[3] = fade;
        continue;
      }
      int i = 0, j = 0;
      if (a == ToHidden) {
        uv.texel_at(t[0] * fw, t[1] * fh, i, j);
      } else {
        const int* d = kAround[a - ToHidden - 1];
        const float* q = uv.px(x + d[0], y + d[1]);
        uv.texel_at(q[0] * fw, q[1] * fh, i, j);
      }
      const float* alb = back_albedo.px(i, j);
      const float share = fade - t[2];
      float* o = hidden.px(x, y);
      // What a compositor weighs the albedo by is the whole share replaced,
      // vis + share (the uv's fourth channel): the albedo is scaled to its part.
      for (int c = 0; c < 3; ++c) o[c] = alb[c] * (share / fade);
      o[3] = share;
      ++n;
    }
    total.fetch_add(n, std::memory_order_relaxed);
  });
  return total.load();
}

void positive_bin_means(const float* values, std::ptrdiff_t row_stride, std::ptrdiff_t col_stride, int rows,
                        int cols, const int* row_bin, const int* col_bin, int bin_rows, int bin_cols, float* out,
                        int threads) {
  if (rows < 0 || cols < 0 || bin_rows < 1 || bin_cols < 1)
    throw InvalidArgument("bins", "expected a grid and at least one bin each way");
  auto check = [](const int* bin, int n, int bins, const char* name) {
    for (int k = 0; k < n; ++k)
      if (bin[k] < 0 || bin[k] >= bins || (k > 0 && bin[k] < bin[k - 1]))
        throw InvalidArgument(name, "expected bin indices in [0, " + std::to_string(bins) +
                                        ") that never decrease, got " + std::to_string(bin[k]) + " at " +
                                        std::to_string(k));
  };
  check(row_bin, rows, bin_rows, "row_bins");
  check(col_bin, cols, bin_cols, "col_bins");
  std::fill(out, out + static_cast<size_t>(bin_rows) * bin_cols, 0.0f);
  // The runs of rows, each a bin of the output's row.
  std::vector<int> run_start;
  for (int r = 0; r < rows; ++r)
    if (r == 0 || row_bin[r] != row_bin[r - 1]) run_start.push_back(r);
  run_start.push_back(rows);
  const int runs = static_cast<int>(run_start.size()) - 1;
  parallel_rows(0, runs, threads, [&](int k) {
    const int r0 = run_start[k], r1 = run_start[k + 1];
    std::vector<float> sum(static_cast<size_t>(cols));
    std::vector<int> count(static_cast<size_t>(cols));
    for (int c = 0; c < cols; ++c) {
      ReduceatSum s;
      int n = 0;
      for (int r = r0; r < r1; ++r) {
        const float v = values[r * row_stride + c * col_stride];
        s.add(v < 0.0f ? 0.0f : v);  // numpy's maximum(v, 0): a NaN stays
        n += v > 0.0f;
      }
      sum[c] = s.value();
      count[c] = n;
    }
    float* row = out + static_cast<size_t>(row_bin[r0]) * bin_cols;
    for (int c0 = 0; c0 < cols;) {
      int c1 = c0;
      ReduceatSum s;
      int n = 0;
      for (; c1 < cols && col_bin[c1] == col_bin[c0]; ++c1) {
        s.add(sum[c1]);
        n += count[c1];
      }
      row[col_bin[c0]] = n > 0 ? static_cast<float>(static_cast<double>(s.value()) / n) : 0.0f;
      c0 = c1;
    }
  });
}

void reweight_hit_specular(Image& uv, const Image& weight, const TraceInputs& in, int threads) {
  const Image& pos = in.position;
  const Image& nrm = in.normal;
  const Image& spec = *in.specular;
  const int w = uv.width, h = uv.height;
  const float fw = static_cast<float>(w), fh = static_cast<float>(h);
  const CameraEye eye = camera_eye(in.projection);
  const float* table = env_brdf_table().data();  // built once, before the workers share it
  auto dot = [](const float* a, const float* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  parallel_rows(0, h, threads, [&](int y) {
    for (int x = 0; x < w; ++x) {
      float* o = uv.px(x, y);
      if (!(o[2] > 0.0f)) continue;  // no hit (a hidden side has vis 0 here)
      int i = 0, j = 0;
      if (!uv.texel_at(o[0] * fw, o[1] * fh, i, j)) continue;
      const float* sh = spec.px(i, j);
      if (!is_reflective(sh)) continue;  // the hit shows no engine specular
      const float* p = pos.px(x, y);
      float d[3];
      incident_toward(eye, p, d);
      const float* n = nrm.px(x, y);
      const float* nh = nrm.px(i, j);
      // -ray . n(hit) for the unit vectors, from the unnormalised ones: the
      // mirror of d about n is d - 2 (d.n / n.n) n.
      const float nn = dot(n, n);
      const float nv = -(dot(d, nh) - 2.0f * dot(d, n) * dot(n, nh) / nn) / std::sqrt(dot(d, d) * dot(nh, nh));
      if (!(nv - nv == 0.0f)) continue;  // a zero or non-finite vector
      float wr[3];
      split_sum_weight(table, sh, std::min(std::max(nv, 0.0f), 1.0f), wr);
      const float along_ray = (wr[0] + wr[1] + wr[2]) / 3.0f;
      // The weight image's alpha is the lod by now: the mean of its rgb.
      // Only the part of the hit's specular that is still the world colour:
      // where the hit has a reflection of its own (its vis), the second
      // bounce puts that in, at the camera's weight.
      const float* wc = weight.px(i, j);
      const float own = std::min(std::max(uv.px(i, j)[2], 0.0f), 1.0f);
      const float k = ((wc[0] + wc[1] + wc[2]) / 3.0f - along_ray) * (1.0f - own);
      if (k - k == 0.0f) o[3] += o[2] * k;
    }
  });
}

CompositeLayers composite_layers(Backend& backend, const TraceInputs& in, const TraceOptions& opt,
                                 int threads, const Image* back_albedo, bool world_specular) {
  require_trace_inputs(in, opt);
  if (!in.specular) throw InvalidArgument("specular", "composite_layers needs the specular buffer");
  const Image& spec = *in.specular;
  CompositeLayers out;
  std::atomic<uint64_t> reflective{0};
  parallel_rows(0, spec.height, threads, [&](int y) {
    uint64_t n = 0;
    for (int x = 0; x < spec.width; ++x) n += texel_seen(in.position.px(x, y)) && is_reflective(spec.px(x, y));
    reflective.fetch_add(n, std::memory_order_relaxed);
  });
  out.reflective_pixels = reflective.load();
  if (out.reflective_pixels == 0) {
    out.uv = Image(spec.width, spec.height);
    out.weight = Image(spec.width, spec.height);
    if (back_albedo) out.hidden = Image(spec.width, spec.height);
    return out;
  }
  out.uv = backend.trace(in, opt);
  // Before the last pass overwrites the trace's fourth channel, which tells
  // an occluder from a hit.
  if (back_albedo) {
    out.hidden = hidden_sides(out.uv, *back_albedo, out.hidden_pixels, threads);
    if (opt.march == March::Hiz)
      out.hidden_pixels += settle_uncertain_shares(out.uv, out.hidden, *back_albedo, threads);
  }
  out.weight = backend.specular_weight(in.position, in.normal, spec, in.projection);
  std::atomic<bool> rough{false};
  // The lod from the trace's own uv, before its misses are continued.
  const MirrorScale mirror = mirror_scale(in.position, in.projection);
  parallel_rows(0, spec.height, threads, [&](int y) {
    bool any = false;
    for (int x = 0; x < spec.width; ++x) {
      const float* s = spec.px(x, y);
      const float lod =
          is_reflective(s) ? cone_lod_at(x, y, spec.width, spec.height, out.uv.px(x, y), s, &mirror) : 0.0f;
      out.weight.px(x, y)[3] = lod;
      any = any || lod > 0.0f;
    }
    if (any) rough.store(true, std::memory_order_relaxed);
  });
  out.any_rough = rough.load();
  if (out.any_rough) continue_lod_into_misses(out.weight, out.uv, spec, in.position, threads);
  // The hidden sides and the lod above came from the trace's own uv; the
  // colour is read inside the objects' outlines.
  read_inside_outlines(out.uv, in.position, in.back_position, opt.thickness, threads);
  continue_missing_uv(out.uv, 2, threads);
  // Until here a hidden side counted as a hit: it keeps its lod and its uv.
  // Now its colour leaves the uv's vis for the hidden image, and alpha says
  // how much of the engine's specular the pixel replaces, by either.
  const bool hidden = out.hidden_pixels > 0;
  parallel_rows(0, spec.height, threads, [&](int y) {
    for (int x = 0; x < spec.width; ++x) {
      float* o = out.uv.px(x, y);
      if (hidden && out.hidden.px(x, y)[3] > 0.0f) {
        // A hidden side alone, or beside a hit's own share (settle_uncertain_shares()).
        if (o[3] == hiz::kEnteredHidden) o[2] = 0.0f;
        o[3] = o[2] + out.hidden.px(x, y)[3];
      } else {
        o[3] = o[2];
      }
    }
  });
  if (world_specular) reweight_hit_specular(out.uv, out.weight, in, threads);
  return out;
}

}  // namespace glint
