// The seed chapter's two-pass march ("seed"), ported to Blender's camera
// space (view distance = -z). The only departures from the seed are the four
// fixes of docs/conventions.md, each marked FIX n below, plus work skipping
// that cannot change the result (marked SKIP). Its GL form is trace_seed.frag
// beside this file; its row of the table of marches is at the end.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "cpu/march.h"
#include "cpu/ray.h"
#include "glint/marches.h"
#include "parallel.h"

namespace glint::cpu {
namespace {

// SKIP: the range of first-pass sample indices k (1..n) whose sample can lie
// on the image. Samples off the image are misses (FIX 3), and a straight line
// that has left the image never comes back, so only this range is probed;
// a huge max_distance then costs no more than the pixels the ray crosses.
// A one-pixel margin keeps the range conservative against float rounding.
void onscreen_range(double sx, double sy, double ix, double iy, int64_t n, double w, double h,
                    int64_t& k0, int64_t& k1) {
  double lo = 1.0, hi = static_cast<double>(n);
  auto clip_axis = [&](double s0, double inc, double size) {
    const double a = -1.0, b = size + 1.0;
    if (inc == 0.0) {
      // Empty. Not lo - 1: past 2^53 that equals lo, and the range read as
      // non-empty with bounds no int64 holds (found by fuzz_trace).
      if (s0 < a || s0 > b) hi = 0.0;  // lo >= 1 always
      return;
    }
    double t0 = (a - s0) / inc, t1 = (b - s0) / inc;
    if (t0 > t1) std::swap(t0, t1);
    lo = std::fmax(lo, t0);
    hi = std::fmin(hi, t1);
  };
  clip_axis(sx, ix, w);
  clip_axis(sy, iy, h);
  if (!(lo <= hi)) {
    k0 = 1;
    k1 = 0;
    return;
  }
  k0 = static_cast<int64_t>(std::floor(lo));
  k1 = static_cast<int64_t>(std::ceil(hi));
  if (k0 < 1) k0 = 1;
  if (k1 > n) k1 = n;
}

// Writes (u, v, visibility, visibility) for pixel (x, y); (0, 0, 0, 0) where
// nothing was seen, the normal is zero, or the ray cannot be projected.
void march_seed(const MarchSetup& s, int x, int y, float out[4]) {
  out[0] = out[1] = out[2] = out[3] = 0.0f;
  V3 from, unit_from, normal;
  if (!read_origin(s, x, y, from, unit_from, normal)) return;

  const Image& pos = *s.position;
  const float tex_w = static_cast<float>(pos.width), tex_h = static_cast<float>(pos.height);
  const float max_distance = s.opt.max_distance;
  const float thickness = s.opt.thickness;

  const V3 pivot = normalize(reflect(unit_from, normal));
  if (!finite(pivot)) return;

  const float ray_length = clipped_length(s, from, pivot, max_distance);
  if (ray_length < 0.0f) return;
  const V3 start_view = from;
  const V3 end_view = from + pivot * ray_length;

  float start_frag[2], end_frag[2];
  if (!to_frag(s.proj, start_view, tex_w, tex_h, start_frag)) return;
  if (!to_frag(s.proj, end_view, tex_w, tex_h, end_frag)) return;

  float frag[2] = {start_frag[0], start_frag[1]};
  float uv[2] = {frag[0] / tex_w, frag[1] / tex_h};

  const float delta_x = end_frag[0] - start_frag[0];
  const float delta_y = end_frag[1] - start_frag[1];
  // FIX 1: a branch instead of mix() of two divisions, one of which is 0/0
  // for axis-aligned rays.
  const bool use_x = std::fabs(delta_x) >= std::fabs(delta_y);
  const float delta = (use_x ? std::fabs(delta_x) : std::fabs(delta_y)) * clamp01(s.opt.resolution);
  const float inc_x = delta_x / std::fmax(delta, 0.001f);
  const float inc_y = delta_y / std::fmax(delta, 0.001f);

  const float start_vd = view_distance(start_view);
  const float end_vd = view_distance(end_view);
  const bool perspective = s.kind == ProjectionKind::Perspective;
  // Depth along the ray at screen fraction t. Perspective: the seed's
  // perspective-correct formula. Orthographic: w is constant, so depth is
  // linear in t. Any other projection: interpolate 1/w, which reduces to
  // both of the above.
  float start_w = 1.0f, end_w = 1.0f;
  if (s.kind == ProjectionKind::General) {
    float c[4];
    clip_of(s.proj, start_view, c);
    start_w = c[3];
    clip_of(s.proj, end_view, c);
    end_w = c[3];
  }
  auto ray_depth = [&](float t) -> float {
    if (perspective) return (start_vd * end_vd) / mixf(end_vd, start_vd, t);
    if (s.kind == ProjectionKind::Orthographic) return mixf(start_vd, end_vd, t);
    return mixf(start_vd / start_w, end_vd / end_w, t) / mixf(1.0f / start_w, 1.0f / end_w, t);
  };
  auto search_of = [&](float fx, float fy) {
    return use_x ? (fx - start_frag[0]) / delta_x : (fy - start_frag[1]) / delta_y;
  };

  float search0 = 0.0f, search1 = 0.0f;
  int hit0 = 0, hit1 = 0;
  float depth = thickness;
  long probe = -1;  // texel of the last probe; the seed's positionTo
  float scene_vd = 0.0f;

  // First pass: samples at start_frag + k * increment, k = 1 .. int(delta).
  // int(delta) of the seed; a ray whose end projects absurdly far off-screen
  // (an end point grazing the near plane) is capped before the conversion
  // overflows. Only the on-screen samples are probed anyway.
  const int64_t n = delta < 4.0e18f ? static_cast<int64_t>(delta) : static_cast<int64_t>(4.0e18);
  if (n > 0) {
    int64_t k0, k1;
    onscreen_range(start_frag[0], start_frag[1], inc_x, inc_y, n, tex_w, tex_h, k0, k1);
    // The samples before k0 were all misses: search0 holds the last of them.
    if (k0 > 1 && k0 <= k1) {
      const float kf = static_cast<float>(k0 - 1);
      search0 = search_of(start_frag[0] + kf * inc_x, start_frag[1] + kf * inc_y);
    }
    // At most (size + 2) * resolution + 2 samples fall on the image, so the
    // cap below never binds for a finite ray. It is there, as in the shader,
    // for an increment of inf / inf = NaN (a ray whose two ends project
    // ~1e38 pixels apart): onscreen_range() cannot narrow a NaN line, and
    // probing int(delta) ~ 4e18 of its samples would never end.
    const int64_t side = pos.width > pos.height ? pos.width : pos.height;
    const int64_t count = k1 >= k0 ? std::min<int64_t>(k1 - k0 + 1, side + 8) : 0;
    for (int64_t i = 0; i < count; ++i) {
      const float kf = static_cast<float>(k0 + i);
      frag[0] = start_frag[0] + kf * inc_x;
      frag[1] = start_frag[1] + kf * inc_y;
      uv[0] = frag[0] / tex_w;
      uv[1] = frag[1] / tex_h;
      probe = fetch_texel(s, uv[0], uv[1], scene_vd);
      search1 = search_of(frag[0], frag[1]);
      depth = ray_depth(search1) - scene_vd;
      if (probe >= 0 && depth > 0.0f && depth < thickness) {
        hit0 = 1;
        break;
      }
      search0 = search1;
    }
    if (!hit0) {
      // The seed's state after its last (k = n) sample, which may have been
      // skipped as off-screen: its uv is what the seed reports.
      const float kf = static_cast<float>(n);
      frag[0] = start_frag[0] + kf * inc_x;
      frag[1] = start_frag[1] + kf * inc_y;
      uv[0] = frag[0] / tex_w;
      uv[1] = frag[1] / tex_h;
      search1 = search_of(frag[0], frag[1]);
      search0 = search1;
    }
  }

  search1 = search0 + ((search1 - search0) / 2.0f);

  // Second pass: the chapter's bisection.
  const int steps = s.opt.steps * hit0;
  float last_probe = -1.0f;
  for (int i = 0; i < steps; ++i) {
    // SKIP: once search0 == search1 and that point was just probed, every
    // further step probes it again with the same outcome.
    if (search0 == search1 && search1 == last_probe) break;
    last_probe = search1;
    frag[0] = mixf(start_frag[0], end_frag[0], search1);
    frag[1] = mixf(start_frag[1], end_frag[1], search1);
    uv[0] = frag[0] / tex_w;
    uv[1] = frag[1] / tex_h;
    probe = fetch_texel(s, uv[0], uv[1], scene_vd);
    depth = ray_depth(search1) - scene_vd;
    if (probe >= 0 && depth > 0.0f && depth < thickness) {
      hit1 = 1;
      search1 = search0 + ((search1 - search0) / 2.0f);
    } else {
      const float temp = search1;
      search1 = search1 + ((search1 - search0) / 2.0f);
      search0 = temp;
    }
  }

  float visibility = 0.0f;
  // FIX 4: without a hit the product is zero; evaluating its other terms
  // could divide by a zero thickness or max_distance.
  if (hit1) {
    float position_to[4];
    texel_at(s, probe, position_to);
    const V3 to = {position_to[0], position_to[1], position_to[2]};
    visibility = static_cast<float>(hit1) * position_to[3] *
                 (1.0f - std::fmax(dot(unit_from * -1.0f, pivot), 0.0f)) *
                 (1.0f - clamp01(depth / thickness)) *
                 (1.0f - clamp01(length(to - from) / max_distance)) *
                 ((uv[0] < 0.0f || uv[0] > 1.0f) ? 0.0f : 1.0f) *
                 ((uv[1] < 0.0f || uv[1] > 1.0f) ? 0.0f : 1.0f);
    visibility = clamp01(visibility);
    if (!finite(visibility)) visibility = 0.0f;
  }
  if (!finite(uv[0]) || !finite(uv[1])) return;
  out[0] = uv[0];
  out[1] = uv[1];
  out[2] = visibility;
  out[3] = visibility;
}

Image trace_seed(const TraceInputs& in, const TraceOptions& opt, int threads) {
  return trace_pixels(in, opt, threads, march_seed);
}

}  // namespace
}  // namespace glint::cpu

namespace glint {

MarchInfo glint_march_seed() {
  MarchInfo m;
  m.name = "seed";
  m.description = "The seed chapter's two-pass march: a coarse pass over a share of the pixels, then bisection";
  m.knobs = {{"max_distance", "length of the reflected ray, view units; also fades the reflection"},
             {"resolution", "share of the pixels the ray crosses on screen that the coarse pass visits"},
             {"steps", "bisection iterations after the first coarse hit"},
             {"thickness", "how far behind the depth buffer a sample still counts as a hit, view units"}};
  m.scratch_per_pixel = 4;  // one float view distance per texel
  m.cpu = &cpu::trace_seed;
  m.gl_program = "trace_seed.frag";
  return m;
}

}  // namespace glint
