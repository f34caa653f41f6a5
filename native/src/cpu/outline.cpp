// Antialiased outlines: finding the pixels and resolving their rays (outline.h).
#include "outline.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "glint/material.h"
#include "parallel.h"
#include "ray.h"

namespace glint::cpu {
namespace {

// Pixel (x, y) is on a reflection's outline when its report is a hit and a
// neighbour's on the same surface a miss or a hidden side entered, or the
// other way round (opposite_reports()), and the
// pixel's reflection is sharp there: where the cone blur's footprint at the
// hit spans more than a pixel (cone_lod_at() > 0), the blur already spreads
// the edge over it, and rays inside the pixel would buy nothing.
// `reports` holds report_of() of every pixel, a byte each. They are compared
// first: most pixels agree with all four neighbours, and the G-buffer is then
// never read.
bool on_outline(const TraceInputs& in, const Image& out, const unsigned char* reports, int x, int y) {
  const int width = out.width, height = out.height;
  const auto report = [&](int i, int j) { return reports[static_cast<size_t>(j) * width + i]; };
  const unsigned char own = report(x, y);
  const Report r = static_cast<Report>(own);
  if (r == Report::Other) return false;
  const int nb[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
  bool differs[4] = {false, false, false, false};
  bool any = false;
  for (int k = 0; k < 4; ++k) {
    const int* q = nb[k];
    if (q[0] < 0 || q[1] < 0 || q[0] >= width || q[1] >= height) continue;
    any |= differs[k] = opposite_reports(own, report(q[0], q[1]));
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

#if defined(__SSE2__)
// report_of() of pixels [0, n) of a row of reports, n the width rounded down
// to 16, sixteen at a time in SSE2 (every x86-64 CPU has it); returns n.
// Compares are exact, so the bytes are report_of()'s. One pixel at a time,
// the row's bytes took a fiftieth of a balanced trace.
int report_row_sse2(const float* o, int width, unsigned char* row) {
  static_assert(static_cast<int>(Report::Miss) == 0 && static_cast<int>(Report::Hit) == 1 &&
                    static_cast<int>(Report::Other) == 2 && static_cast<int>(Report::Entered) == 3,
                "the bytes made below");
  const int n = width - width % 16;
  const __m128 zero = _mm_setzero_ps();
  const __m128 entered = _mm_set1_ps(hiz::kEnteredHidden);
  const __m128i one = _mm_set1_epi32(1), two = _mm_set1_epi32(2), three = _mm_set1_epi32(3);
  for (int x0 = 0; x0 < n; x0 += 16) {
    __m128i r[4];
    for (int q = 0; q < 4; ++q) {
      const float* p = o + 4 * static_cast<size_t>(x0 + 4 * q);
      // (z, w) of four pixels: z0 w0 z1 w1 and z2 w2 z3 w3, then split.
      const __m128 a = _mm_shuffle_ps(_mm_loadu_ps(p), _mm_loadu_ps(p + 4), _MM_SHUFFLE(3, 2, 3, 2));
      const __m128 b = _mm_shuffle_ps(_mm_loadu_ps(p + 8), _mm_loadu_ps(p + 12), _MM_SHUFFLE(3, 2, 3, 2));
      const __m128 z = _mm_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0)), w = _mm_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1));
      const __m128i hit = _mm_castps_si128(_mm_cmpgt_ps(w, zero));
      const __m128i miss = _mm_castps_si128(_mm_and_ps(_mm_cmpeq_ps(z, zero), _mm_cmpeq_ps(w, zero)));
      const __m128i ent = _mm_castps_si128(_mm_cmpeq_ps(w, entered));
      // Hit 1, Entered 3, else Miss 0, else Other 2: the three tests exclude
      // each other (w > 0, w == -1, w == 0).
      r[q] = _mm_or_si128(_mm_or_si128(_mm_and_si128(hit, one), _mm_and_si128(ent, three)),
                          _mm_andnot_si128(_mm_or_si128(_mm_or_si128(hit, miss), ent), two));
    }
    const __m128i bytes = _mm_packus_epi16(_mm_packs_epi32(r[0], r[1]), _mm_packs_epi32(r[2], r[3]));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(row + x0), bytes);
  }
  return n;
}
#endif

}  // namespace

void report_row(const float* o, int width, unsigned char* bytes) {
  int x = 0;
#if defined(__SSE2__)
  x = report_row_sse2(o, width, bytes);
#endif
  for (; x < width; ++x) bytes[x] = static_cast<unsigned char>(report_of(o + 4 * static_cast<size_t>(x)));
}

bool same_surface(const TraceInputs& in, const float* p, const float* n, int qx, int qy) {
  if (in.specular && !is_reflective(in.specular->px(qx, qy))) return false;
  const float* pq = in.position.px(qx, qy);
  const float* nq = in.normal.px(qx, qy);
  if (!texel_seen(pq) || !(std::fabs(pq[2] - p[2]) <= hiz::kReuseDepth * std::fabs(p[2]))) return false;
  return normals_agree(n, nq);
}

std::vector<std::vector<int>> outline_pixels(const TraceInputs& in, const Image& out, int threads,
                                             std::vector<std::vector<unsigned char>>* beside_hidden) {
  const int width = out.width, height = out.height;
  std::vector<unsigned char> reports(out.pixel_count());
  parallel_rows(0, height, threads, [&](int y) {
    report_row(out.px(0, y), width, reports.data() + static_cast<size_t>(y) * width);
  });
  // Opposite reports side by side are on_outline()'s first test. Done on
  // whole rows in byte lanes, so that the nine pixels in ten nowhere near an
  // outline cost a few instructions; rows past the image are all Other, which
  // is opposite to nothing.
  const std::vector<unsigned char> none(static_cast<size_t>(width), static_cast<unsigned char>(Report::Other));
  std::vector<std::vector<int>> edges(static_cast<size_t>(height));
  if (beside_hidden) beside_hidden->assign(static_cast<size_t>(height), {});
  const unsigned char entered = static_cast<unsigned char>(Report::Entered);
  parallel_rows(0, height, threads, [&](int y) {
    const unsigned char* r = reports.data() + static_cast<size_t>(y) * width;
    const unsigned char* up = y + 1 < height ? r + width : none.data();
    const unsigned char* down = y > 0 ? r - width : none.data();
    // The row padded with an Other on either side, so that one loop with no
    // edge cases (which the compiler vectorises) covers it.
    std::vector<unsigned char> padded(static_cast<size_t>(width) + 2, static_cast<unsigned char>(Report::Other));
    std::copy(r, r + width, padded.begin() + 1);
    std::vector<unsigned char> near(static_cast<size_t>(width) + 8, 0);  // whole 8-byte words to scan
    const unsigned char* c = padded.data() + 1;
    unsigned char* nr = near.data();
    const int n = width;  // a local bound: the captured width would be reloaded after each store
    for (int x = 0; x < n; ++x) {
      const unsigned char a = c[x];
      nr[x] = static_cast<unsigned char>(opposite_reports(a, c[x - 1]) | opposite_reports(a, c[x + 1]) |
                                         opposite_reports(a, up[x]) | opposite_reports(a, down[x]));
    }
    // Eight pixels a word: most words are all zero.
    for (int x0 = 0; x0 < n; x0 += 8) {
      std::uint64_t word;
      std::memcpy(&word, nr + x0, sizeof word);
      if (!word) continue;
      for (int x = x0; x < std::min(n, x0 + 8); ++x)
        if (nr[x] && on_outline(in, out, reports.data(), x, y)) {
          edges[y].push_back(x);
          if (beside_hidden)
            (*beside_hidden)[y].push_back(static_cast<unsigned char>(
                (c[x] == entered) | (c[x - 1] == entered) | (c[x + 1] == entered) | (up[x] == entered) |
                (down[x] == entered)));
        }
    }
  });
  return edges;
}

void resolve_outline(const float* c, const float* samples, int k, float w, float h, float* o, bool one_hit_uv) {
  const float* ref = c[3] > 0.0f ? c : nullptr;
  for (int j = 0; j < k && !ref; ++j)
    if (samples[4 * j + 3] > 0.0f) ref = samples + 4 * j;
  if (!ref) return;
  float su = 0.0f, sv = 0.0f, sw = 0.0f;
  bool miss = false, entered = false;
  // Every read happens before the first write: `o` may be `c`.
  auto add = [&](const float* s) {
    const Report r = report_of(s);
    miss = miss || r == Report::Miss;
    entered = entered || r == Report::Entered;
    // Where the pixel spans the open and a hidden side too, the share the
    // hits leave has no one owner (composite_layers() would show the open's).
    if (r != Report::Hit) return (r == Report::Miss || r == Report::Entered) && !(miss && entered);
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
  // Beside a hidden side, one hit's uv (outline.h says why).
  const bool one = one_hit_uv || entered;
  o[0] = one ? ref[0] : su / sw;
  o[1] = one ? ref[1] : sv / sw;
  o[2] = o[3] = vis;
}

}  // namespace glint::cpu
