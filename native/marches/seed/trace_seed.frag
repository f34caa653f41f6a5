#version 430 core
// The seed chapter's two-pass march ("seed"): a coarse pass over screen
// pixels, then bisection. A line-by-line port of march_seed() in
// native/src/cpu/march_seed.cpp, which carries the reasoning behind each step;
// The fixes of docs/conventions.md are marked FIX n, work skipping that cannot change the
// result SKIP. Output: (u, v, visibility, visibility).
#include "common.glsl"
#include "fragment.glsl"
#include "trace_common.glsl"

uniform float u_resolution;  // already clamped to [0, 1] on the host

layout(location = 0) out vec4 out_uv;

// Start and end of the ray in pixels; set once in main.
vec2 g_start_frag;
vec2 g_end_frag;
bool g_use_x;
float g_delta_x;
float g_delta_y;
float g_start_vd;
float g_end_vd;
float g_start_w;
float g_end_w;

// Depth along the ray at screen fraction t: perspective-correct for a
// perspective camera, linear for an orthographic one, 1/w-interpolated for
// any other projection.
float ray_depth(float t) {
  if (u_kind == KIND_PERSPECTIVE) {
    precise float d = (g_start_vd * g_end_vd) / mixf(g_end_vd, g_start_vd, t);
    return d;
  }
  if (u_kind == KIND_ORTHOGRAPHIC) return mixf(g_start_vd, g_end_vd, t);
  precise float a = g_start_vd / g_start_w;
  precise float b = g_end_vd / g_end_w;
  precise float ia = 1.0 / g_start_w;
  precise float ib = 1.0 / g_end_w;
  precise float d = mixf(a, b, t) / mixf(ia, ib, t);
  return d;
}

float search_of(vec2 frag) {
  precise float s = g_use_x ? (frag.x - g_start_frag.x) / g_delta_x
                            : (frag.y - g_start_frag.y) / g_delta_y;
  return s;
}

// SKIP: the range k0..k1 of first-pass samples that can land on the image
// (with a one-pixel margin), in double like the CPU. Off-image samples are
// misses and a straight line that left the image never returns.
void onscreen_range(double sx, double sy, double ix, double iy, double n, double w, double h,
                    out double k0, out double k1) {
  double lo = 1.0lf;
  double hi = n;
  for (int axis = 0; axis < 2; ++axis) {
    double s0 = axis == 0 ? sx : sy;
    double inc = axis == 0 ? ix : iy;
    double size = axis == 0 ? w : h;
    precise double a = -1.0lf;
    precise double b = size + 1.0lf;
    if (inc == 0.0lf) {
      if (s0 < a || s0 > b) hi = lo - 1.0lf;
      continue;
    }
    precise double t0 = (a - s0) / inc;
    precise double t1 = (b - s0) / inc;
    if (t0 > t1) {
      double t = t0;
      t0 = t1;
      t1 = t;
    }
    lo = max(lo, t0);
    hi = min(hi, t1);
  }
  if (!(lo <= hi)) {
    k0 = 1.0lf;
    k1 = 0.0lf;
    return;
  }
  k0 = max(floor(lo), 1.0lf);
  k1 = min(ceil(hi), n);
}

void main() {
  out_uv = vec4(0.0);
  vec3 from, unit_from, normal;
  if (!read_origin(pixel_coord(), from, unit_from, normal)) return;

  float max_distance = u_max_distance;
  float thickness = u_thickness;

  vec3 pivot = normalize3(reflect3(unit_from, normal));
  if (!finite_v3(pivot)) return;

  float ray_length = clipped_length(from, pivot, max_distance);
  if (ray_length < 0.0) return;
  vec3 start_view = from;
  precise vec3 end_view = from + pivot * ray_length;

  if (!to_frag(start_view, g_start_frag)) return;
  if (!to_frag(end_view, g_end_frag)) return;

  vec2 frag = g_start_frag;
  precise vec2 uv = frag / u_size;

  precise float delta_x = g_end_frag.x - g_start_frag.x;
  precise float delta_y = g_end_frag.y - g_start_frag.y;
  g_delta_x = delta_x;
  g_delta_y = delta_y;
  // FIX 1: a branch instead of mix() of two divisions, one of them 0/0 for
  // axis-aligned rays.
  g_use_x = abs(delta_x) >= abs(delta_y);
  precise float delta = (g_use_x ? abs(delta_x) : abs(delta_y)) * u_resolution;
  precise float inc_x = delta_x / max(delta, 0.001);
  precise float inc_y = delta_y / max(delta, 0.001);

  g_start_vd = view_distance(start_view);
  g_end_vd = view_distance(end_view);
  g_start_w = 1.0;
  g_end_w = 1.0;
  if (u_kind != KIND_PERSPECTIVE && u_kind != KIND_ORTHOGRAPHIC) {
    g_start_w = clip_row(3, start_view);
    g_end_w = clip_row(3, end_view);
  }

  precise float search0 = 0.0;
  precise float search1 = 0.0;
  int hit0 = 0;
  int hit1 = 0;
  precise float depth = thickness;
  vec4 position_to = vec4(from, 1.0);

  // First pass: k = 1 .. int(delta), capped like the CPU before the integer
  // conversion could overflow; double holds every such count exactly enough.
  double n = delta < 4.0e18 ? trunc(double(delta)) : 4.0e18lf;
  if (n > 0.0lf) {
    double k0, k1;
    onscreen_range(double(g_start_frag.x), double(g_start_frag.y), double(inc_x), double(inc_y),
                   n, double(u_size.x), double(u_size.y), k0, k1);
    if (k0 > 1.0lf && k0 <= k1) {
      float kf = float(k0 - 1.0lf);
      search0 = search_of(vec2(g_start_frag.x + kf * inc_x, g_start_frag.y + kf * inc_y));
    }
    // The range spans at most (size + 2) * resolution + 2 samples along the
    // major axis (one sample per 1 / resolution pixels); counting with an int
    // from k0, capped like the CPU loop, keeps the loop finite even where k0
    // is beyond 2^53 or the increment is NaN (inf / inf).
    int count = k1 >= k0 ? int(min(k1 - k0 + 1.0lf, double(max(u_size.x, u_size.y)) + 8.0lf)) : 0;
    for (int i = 0; i < count; ++i) {
      float kf = float(k0 + double(i));
      precise float fx = g_start_frag.x + kf * inc_x;
      precise float fy = g_start_frag.y + kf * inc_y;
      frag = vec2(fx, fy);
      uv = frag / u_size;
      bool seen = fetch_position(uv, position_to);
      search1 = search_of(frag);
      depth = ray_depth(search1) - view_distance(position_to.xyz);
      if (seen && depth > 0.0 && depth < thickness) {
        hit0 = 1;
        break;
      }
      search0 = search1;
    }
    if (hit0 == 0) {
      // The seed's state after its last sample (k = n), which may have been
      // skipped as off-screen: its uv is what the seed reports.
      float kf = float(n);
      precise float fx = g_start_frag.x + kf * inc_x;
      precise float fy = g_start_frag.y + kf * inc_y;
      frag = vec2(fx, fy);
      uv = frag / u_size;
      search1 = search_of(frag);
      search0 = search1;
    }
  }

  search1 = search0 + ((search1 - search0) / 2.0);

  // Second pass: the chapter's bisection.
  int steps = u_steps * hit0;
  float last_probe = -1.0;
  for (int i = 0; i < steps; ++i) {
    // SKIP: once search0 == search1 and that point was just probed, every
    // further step probes it again with the same outcome.
    if (search0 == search1 && search1 == last_probe) break;
    last_probe = search1;
    frag = vec2(mixf(g_start_frag.x, g_end_frag.x, search1), mixf(g_start_frag.y, g_end_frag.y, search1));
    uv = frag / u_size;
    bool seen = fetch_position(uv, position_to);
    depth = ray_depth(search1) - view_distance(position_to.xyz);
    if (seen && depth > 0.0 && depth < thickness) {
      hit1 = 1;
      search1 = search0 + ((search1 - search0) / 2.0);
    } else {
      float temp = search1;
      search1 = search1 + ((search1 - search0) / 2.0);
      search0 = temp;
    }
  }

  precise float visibility = 0.0;
  // FIX 4: without a hit the product is zero; its other terms could divide
  // by a zero thickness or max_distance.
  if (hit1 != 0) {
    vec3 to = position_to.xyz;
    precise float facing = 1.0 - max(dot3(unit_from * -1.0, pivot), 0.0);
    precise float behind = 1.0 - clamp01(depth / thickness);
    precise float dist = 1.0 - clamp01(length3(to - from) / max_distance);
    precise float in_u = (uv.x < 0.0 || uv.x > 1.0) ? 0.0 : 1.0;
    precise float in_v = (uv.y < 0.0 || uv.y > 1.0) ? 0.0 : 1.0;
    visibility = float(hit1) * position_to.w * facing * behind * dist * in_u * in_v;
    visibility = clamp01(visibility);
    if (!finite_f(visibility)) visibility = 0.0;
  }
  if (!finite_f(uv.x) || !finite_f(uv.y)) return;
  out_uv = vec4(uv, visibility, visibility);
}
