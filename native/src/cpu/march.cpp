// The seed chapter's two-pass march ("seed") and the book's older linear
// march ("linear"), ported to Blender's camera space (view distance = -z).
// The only departures from the seed are SPEC.md's four fixes, each marked
// FIX n below, plus work skipping that cannot change the result (marked SKIP).
#include "march.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "parallel.h"
#include "ray.h"
#include "trace.h"

namespace glint::cpu {
namespace {

// FIX 3: nearest texel at floor(uv * size); outside the image or on an
// unseen texel is a miss. Returns the texel's index (or -1 on a miss) and
// its view distance (0 on a miss: the seed's cleared texel).
inline long fetch_texel(const MarchSetup& s, float u, float v, float& scene_vd) {
  const Image& pos = *s.position;
  const float fx = std::floor(u * static_cast<float>(pos.width));
  const float fy = std::floor(v * static_cast<float>(pos.height));
  if (fx >= 0.0f && fx < static_cast<float>(pos.width) && fy >= 0.0f &&
      fy < static_cast<float>(pos.height)) {
    const long i = static_cast<long>(fy) * pos.width + static_cast<long>(fx);
    const float vd = s.view_distance[i];
    if (vd == vd) {
      scene_vd = vd;
      return i;
    }
  }
  scene_vd = 0.0f;
  return -1;
}

// The full texel behind a fetch, (0, 0, 0, 0) for a miss.
inline void texel_at(const MarchSetup& s, long i, float out[4]) {
  if (i < 0) {
    out[0] = out[1] = out[2] = out[3] = 0.0f;
    return;
  }
  const float* p = s.position->data.data() + static_cast<size_t>(i) * 4;
  out[0] = p[0]; out[1] = p[1]; out[2] = p[2]; out[3] = p[3];
}

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

}  // namespace

void fill_view_distance(const Image& position, int y, float* out) {
  for (int x = 0; x < position.width; ++x) {
    const float* p = position.px(x, y);
    out[x] = texel_seen(p) ? view_distance({p[0], p[1], p[2]}) : std::numeric_limits<float>::quiet_NaN();
  }
}

MarchSetup make_setup(const Image& position, const Image& normal, const Mat4& projection,
                      const TraceOptions& opt, const float* view_distance) {
  MarchSetup s;
  s.position = &position;
  s.normal = &normal;
  s.view_distance = view_distance;
  for (int i = 0; i < 16; ++i) {
    s.projd[i] = projection.m[i];
    s.proj[i] = static_cast<float>(projection.m[i]);
  }
  s.kind = classify_projection(projection);
  s.opt = opt;
  const CameraEye ce = camera_eye(projection);
  s.eye_kind = ce.kind;
  for (int k = 0; k < 3; ++k) s.eye[k] = ce.eye[k];
  return s;
}

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

void march_linear(const MarchSetup& s, int x, int y, float out[4]) {
  out[0] = out[1] = out[2] = out[3] = 0.0f;
  V3 from, unit_from, normal;
  if (!read_origin(s, x, y, from, unit_from, normal)) return;
  const int steps = s.opt.steps;
  if (steps <= 0) return;

  const V3 reflection = normalize(reflect(unit_from, normal));
  if (!finite(reflection)) return;
  const float thickness = s.opt.thickness;
  float max_distance = s.opt.max_distance;
  float step_size = max_distance / static_cast<float>(steps);
  float count = 1.0f;

  for (int i = 0; i < steps; ++i) {
    const float distance = count * step_size;
    if (distance > max_distance) break;
    const V3 sample = from + reflection * distance;
    float c[4];
    clip_of(s.proj, sample, c);
    // A sample behind the eye (w <= 0) is outside the frustum too: without
    // this test its divided coordinates would flip sign and look inside.
    if (!(c[3] > 0.0f)) break;
    const float ox = c[0] / c[3] * 0.5f + 0.5f;
    const float oy = c[1] / c[3] * 0.5f + 0.5f;
    const float oz = c[2] / c[3];
    if (!(ox >= 0.0f && oy >= 0.0f && oz >= -1.0f && ox <= 1.0f && oy <= 1.0f && oz <= 1.0f)) break;

    float scene_vd;
    const bool seen = fetch_texel(s, ox, oy, scene_vd) >= 0;
    const float sample_vd = view_distance(sample);
    if (seen && sample_vd >= scene_vd && sample_vd <= scene_vd + thickness) {
      const float visibility = clamp01(1.0f - std::fmax(dot(reflection, unit_from * -1.0f), 0.0f));
      // The book writes (u, v, visibility, 1); Glint's buffer contract is
      // (u, v, visibility, visibility) for every march.
      out[0] = ox;
      out[1] = oy;
      out[2] = visibility;
      out[3] = visibility;
      // Step back to the last miss and approach with smaller steps, exactly
      // as the book does (the restart distance is count * new step size).
      count -= 1.0f;
      max_distance = distance;
      const float previous_distance = count * step_size;
      const float steps_left = std::fmax(static_cast<float>(steps - i), 1.0f);
      step_size = (max_distance - previous_distance) / steps_left;
    } else {
      count += 1.0f;
    }
  }
}

std::vector<float> view_distances(const Image& position, int threads) {
  std::vector<float> vd(position.pixel_count());
  parallel_rows(0, position.height, threads, [&](int y) {
    fill_view_distance(position, y, vd.data() + static_cast<size_t>(y) * position.width);
  });
  return vd;
}

namespace {

// The seed and the linear march share everything but the per-pixel march.
template <class PerPixel>
Image trace_pixels(const TraceInputs& in, const TraceOptions& opt, int threads, PerPixel&& march) {
  Image out = Image::uninitialized(in.position.width, in.position.height);  // each march writes its pixel
  const std::vector<float> vd = view_distances(in.position, threads);
  const MarchSetup setup = make_setup(in.position, in.normal, in.projection, opt, vd.data());
  const Image* spec = in.specular;
  parallel_rows(0, out.height, threads, [&](int y) {
    for (int x = 0; x < out.width; ++x) {
      float* o = out.px(x, y);
      if (spec && !is_reflective(spec->px(x, y))) {  // the seed returns early here
        o[0] = o[1] = o[2] = o[3] = 0.0f;
        continue;
      }
      march(setup, x, y, o);
    }
  });
  return out;
}

}  // namespace

Image trace_seed(const TraceInputs& in, const TraceOptions& opt, int threads) {
  return trace_pixels(in, opt, threads, march_seed);
}

Image trace_linear(const TraceInputs& in, const TraceOptions& opt, int threads) {
  return trace_pixels(in, opt, threads, march_linear);
}

}  // namespace glint::cpu
