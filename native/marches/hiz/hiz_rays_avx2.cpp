// The pixels' own rays (march_hiz.cpp's make_ray(): read_origin(),
// make_ray_from() and clipped_length() in ray.cpp, its tries included) for
// x86-64 CPUs with AVX2: eight pixels at once, one per lane. Like the other
// *_avx2.cpp files, this one alone is built with -mavx2 and not -mfma and
// includes no inline functions but hiz_lanes_avx2.h's. Each lane does the
// scalar rule's float and double operations in its order, so the rays are
// the scalar ones bit for bit (test_hiz_walk compares the two).
//
// Why: a ray's set-up is some 560 instructions one at a time, about a sixth
// of a single-thread balanced trace at 1080p, all of it straight-line
// arithmetic but for its checks and one loop (the near-plane clip's search
// for an end point that rounds in front of the plane), which the lanes run
// together.
#include <immintrin.h>

#include "hiz_base.h"
#include "hiz_lanes_avx2.h"

namespace glint::cpu {
namespace {

typedef double VD __attribute__((vector_size(32)));
typedef long long VL __attribute__((vector_size(32)));

__attribute__((always_inline)) inline VD splatd(double v) { return VD{v, v, v, v}; }
// The low and high four lanes of v in double (exact).
__attribute__((always_inline)) inline VD low(VF v) {
  return reinterpret_cast<VD>(_mm256_cvtps_pd(_mm256_castps256_ps128(reinterpret_cast<__m256>(v))));
}
__attribute__((always_inline)) inline VD high(VF v) {
  return reinterpret_cast<VD>(_mm256_cvtps_pd(_mm256_extractf128_ps(reinterpret_cast<__m256>(v), 1)));
}
// static_cast<float>() of two halves, rounded to nearest as the scalar cast.
__attribute__((always_inline)) inline VF join(VD lo, VD hi) {
  return reinterpret_cast<VF>(_mm256_set_m128(_mm256_cvtpd_ps(reinterpret_cast<__m256d>(hi)),
                                               _mm256_cvtpd_ps(reinterpret_cast<__m256d>(lo))));
}
// Two halves' double masks as one float-lane mask.
__attribute__((always_inline)) inline VI join_mask(VL lo, VL hi) {
  const int bits = _mm256_movemask_pd(reinterpret_cast<__m256d>(lo)) |
                   (_mm256_movemask_pd(reinterpret_cast<__m256d>(hi)) << 4);
  return (VI{1, 2, 4, 8, 16, 32, 64, 128} & bits) != 0;
}

// clip_row() of ray.h.
__attribute__((always_inline)) inline VD clip_row(const double* P, int r, VD x, VD y, VD z) {
  return splatd(P[r * 4 + 0]) * x + splatd(P[r * 4 + 1]) * y + splatd(P[r * 4 + 2]) * z + splatd(P[r * 4 + 3]);
}
// clipped_length()'s near_fn: clip z + w, >= 0 on or in front of the near plane.
__attribute__((always_inline)) inline VD near_of(const double* P, VD x, VD y, VD z) {
  return clip_row(P, 2, x, y, z) + clip_row(P, 3, x, y, z);
}
// A point of the ray in front of the near plane with w > 0, as the scalar
// clip checks it, on four lanes.
__attribute__((always_inline)) inline VL in_front(const double* P, VD x, VD y, VD z) {
  return (near_of(P, x, y, z) >= splatd(0.0)) & (clip_row(P, 3, x, y, z) > splatd(0.0));
}

// One row of clip_of() of ray.h.
__attribute__((always_inline)) inline VF clip_of(const float* P, int r, const VF v[3]) {
  return splat(P[r * 4 + 0]) * v[0] + splat(P[r * 4 + 1]) * v[1] + splat(P[r * 4 + 2]) * v[2] + splat(P[r * 4 + 3]);
}

__attribute__((always_inline)) inline VF dot3(const VF a[3], const VF b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
__attribute__((always_inline)) inline VF vsqrt(VF v) {
  return reinterpret_cast<VF>(_mm256_sqrt_ps(reinterpret_cast<__m256>(v)));
}
// std::min(a, b) of the scalar code: b where b < a, else a.
__attribute__((always_inline)) inline VF min_of(VF a, VF b) { return pick(b < a, b, a); }

__attribute__((always_inline)) inline VF gather(const float* row, VI index) {
  return reinterpret_cast<VF>(_mm256_i32gather_ps(row, reinterpret_cast<__m256i>(index), 4));
}

}  // namespace

void hiz_pixel_rays_avx2(const RayRow& r, const int* xs, int n, RayFields* rays, unsigned char* made) {
  const double* Pd = r.projd;
  const float* P = r.proj;
  const float w = static_cast<float>(r.width), h = static_cast<float>(r.height);
  for (int k0 = 0; k0 < n; k0 += 8) {
    const int m = n - k0 < 8 ? n - k0 : 8;
    VI x{};  // each lane's pixel; lanes past n repeat the first
    for (int l = 0; l < 8; ++l) x[l] = xs[k0 + (l < m ? l : 0)];
    const VI texel = 4 * x;

    // read_origin(): the texel is seen, its normal finite and not zero.
    VF p[4], nr[3];
    for (int c = 0; c < 4; ++c) p[c] = gather(r.position, texel + c);
    for (int c = 0; c < 3; ++c) nr[c] = gather(r.normal, texel + c);
    const VF nn = dot3(nr, nr);
    VI ok = texel_seen(p) & finite(nr[0]) & finite(nr[1]) & finite(nr[2]) & (nn != splat(0.0f));
    VF from[3] = {p[0], p[1], p[2]};

    // incident_direction(): normalize(v) is v * (1 / sqrt(v . v)).
    VF unit[3];
    auto incident = [&]() {
      if (r.eye_kind == 2) {
        for (int c = 0; c < 3; ++c) unit[c] = splat(r.eye[c]);
      } else {
        VF v[3];
        for (int c = 0; c < 3; ++c) v[c] = r.eye_kind == 1 ? from[c] - splat(r.eye[c]) : from[c];
        const VF vv = dot3(v, v);
        ok &= vv != splat(0.0f);
        const VF s = splat(1.0f) / vsqrt(vv);
        for (int c = 0; c < 3; ++c) unit[c] = v[c] * s;
      }
      ok &= finite(unit[0]) & finite(unit[1]) & finite(unit[2]);
    };
    incident();
    if (r.offset) {
      // subpixel_ray(): texel_plane()'s row L of the texel's plane, from the
      // plane normal (not the shading one); the point of that plane under
      // the sample, unprojected; kept within the footprint's depth spread.
      VF pn[3];
      for (int c = 0; c < 3; ++c) pn[c] = gather(r.planes, 3 * x + c);
      const VF zero = splat(0.0f);
      ok &= finite(pn[0]) & finite(pn[1]) & finite(pn[2]) & ((pn[0] != zero) | (pn[1] != zero) | (pn[2] != zero));
      const float* H = r.inv;
      const VF kd = dot3(pn, from);
      VF L[4];
      for (int c = 0; c < 4; ++c)
        L[c] = pn[0] * splat(H[c]) + pn[1] * splat(H[4 + c]) + pn[2] * splat(H[8 + c]) - kd * splat(H[12 + c]);
      ok &= L[2] != zero;
      VF ox, oy;
      for (int l = 0; l < 8; ++l) {
        const int k = k0 + (l < m ? l : 0);
        ox[l] = r.offset[2 * k];
        oy[l] = r.offset[2 * k + 1];
      }
      const VF px = __builtin_convertvector(x, VF);
      const VF sx = (px + (splat(0.5f) + ox)) * splat(2.0f / w) - splat(1.0f);
      const VF sy = (splat(static_cast<float>(r.y)) + (splat(0.5f) + oy)) * splat(2.0f / h) - splat(1.0f);
      const VF sz = -(L[0] * sx + L[1] * sy + L[3]) / L[2];
      VF v[4];
      for (int c = 0; c < 4; ++c)
        v[c] = splat(H[4 * c]) * sx + splat(H[4 * c + 1]) * sy + splat(H[4 * c + 2]) * sz + splat(H[4 * c + 3]);
      const VF at[3] = {v[0] / v[3], v[1] / v[3], v[2] / v[3]};
      const VF d = -from[2];
      ok &= finite(at[0]) & finite(at[1]) & finite(at[2]) &
            (vabs(-at[2] - d) <= splat(r.footprint_spread) * vabs(d));
      for (int c = 0; c < 3; ++c) from[c] = at[c];
      incident();
    }
    VF normal[3];
    {
      const VF s = splat(1.0f) / vsqrt(nn);
      for (int c = 0; c < 3; ++c) normal[c] = nr[c] * s;
    }
    ok &= finite(normal[0]) & finite(normal[1]) & finite(normal[2]);

    // make_ray_from(): dir = normalize(reflect(unit, normal)).
    VF dir[3];
    {
      const VF k = splat(2.0f) * dot3(normal, unit);
      VF rf[3];
      for (int c = 0; c < 3; ++c) rf[c] = unit[c] - normal[c] * k;
      const VF s = splat(1.0f) / vsqrt(dot3(rf, rf));
      for (int c = 0; c < 3; ++c) dir[c] = rf[c] * s;
    }
    ok &= finite(dir[0]) & finite(dir[1]) & finite(dir[2]);

    // clipped_length(), in double four lanes at a time: the origin in front,
    // the length cut where the full ray would cross the near plane.
    VD fd[2][3], dd[2][3], len[2];
    VL front[2];
    for (int c = 0; c < 3; ++c) {
      fd[0][c] = low(from[c]), fd[1][c] = high(from[c]);
      dd[0][c] = low(dir[c]), dd[1][c] = high(dir[c]);
    }
    for (int half = 0; half < 2; ++half) {
      const VD* f = fd[half];
      const VD* d = dd[half];
      const VD n0 = near_of(Pd, f[0], f[1], f[2]);
      front[half] = (n0 >= splatd(0.0)) & (clip_row(Pd, 3, f[0], f[1], f[2]) > splatd(0.0));
      const VD most = splatd(static_cast<double>(r.max_distance));
      const VD n1 = near_of(Pd, f[0] + d[0] * most, f[1] + d[1] * most, f[2] + d[2] * most);
      len[half] = n1 < splatd(0.0) ? most * (n0 / (n0 - n1)) : most;
    }
    ok &= join_mask(front[0], front[1]);
    const VF full = join(len[0], len[1]);
    // The float end point on or in front of the plane: the first try is the
    // full length, which ends it for all but some of the rays the plane cuts,
    // whose end rounds behind it; those lanes try on, shrinking by the scalar
    // rule's steps (the same for every lane), while any is left.
    VF length = full, end[3];
    auto end_at = [&](VF t) {
      for (int c = 0; c < 3; ++c) end[c] = from[c] + dir[c] * t;
      return join_mask(in_front(Pd, low(end[0]), low(end[1]), low(end[2])),
                       in_front(Pd, high(end[0]), high(end[1]), high(end[2])));
    };
    VI settled = end_at(full);
    float shrink = 1.0f / 4194304.0f;  // clipped_length()'s 2^-22
    for (int i = 1; i < 64 && _mm256_movemask_ps(reinterpret_cast<__m256>(ok & ~settled)) != 0; ++i) {
      const VF t = full * splat(1.0f - shrink);
      shrink = shrink * 2.0f > 1.0f ? 1.0f : shrink * 2.0f;
      const VI now = end_at(t) & ~settled;
      length = pick(now, t, length);
      settled |= now;
    }
    // No try left in front: clipped_length()'s 0, which has no ray. `end`
    // holds the last try's points, not each lane's own: made again.
    length = pick(settled, length, splat(0.0f));
    for (int c = 0; c < 3; ++c) end[c] = from[c] + dir[c] * length;
    ok &= length > splat(0.0f);

    // Both ends projected; B = 1 / w.
    const VF c0w = clip_of(P, 3, from), c1w = clip_of(P, 3, end);
    ok &= (c0w > splat(0.0f)) & (c1w > splat(0.0f));
    const VF b0 = splat(1.0f) / c0w, b1 = splat(1.0f) / c1w;
    const VF half = splat(0.5f);
    const VF f0x = (clip_of(P, 0, from) * b0 * half + half) * splat(w);
    const VF f0y = (clip_of(P, 1, from) * b0 * half + half) * splat(h);
    const VF dx = (clip_of(P, 0, end) * b1 * half + half) * splat(w) - f0x;
    const VF dy = (clip_of(P, 1, end) * b1 * half + half) * splat(h) - f0y;
    ok &= finite(f0x) & finite(f0y) & finite(dx) & finite(dy);
    const VF zero = splat(0.0f);
    const VF invx = pick(dx != zero, splat(1.0f) / dx, zero);
    const VF invy = pick(dy != zero, splat(1.0f) / dy, zero);
    const VF nudge = splat(r.cell_nudge);
    const VF nudgex = pick(dx > zero, nudge, pick(dx < zero, -nudge, zero));
    const VF nudgey = pick(dy > zero, nudge, pick(dy < zero, -nudge, zero));
    // Ray::exit() of the image from t_end = 1.
    VF t_end = splat(1.0f);
    t_end = pick(dx != zero, min_of(t_end, (pick(dx > zero, splat(w), zero) - f0x) * invx), t_end);
    t_end = pick(dy != zero, min_of(t_end, (pick(dy > zero, splat(h), zero) - f0y) * invy), t_end);
    ok &= t_end > zero;

    VF a0[3], da[3];
    for (int c = 0; c < 3; ++c) {
      a0[c] = from[c] * b0;
      da[c] = end[c] * b1 - a0[c];
    }
    const VF db = b1 - b0;
    for (int l = 0; l < m; ++l) {
      const int k = k0 + l;
      made[k] = ok[l] ? 1 : 0;
      if (!ok[l]) continue;
      RayFields& o = rays[k];
      o.f0[0] = f0x[l], o.f0[1] = f0y[l];
      o.d[0] = dx[l], o.d[1] = dy[l];
      for (int c = 0; c < 3; ++c) o.a0[c] = a0[c][l], o.da[c] = da[c][l];
      o.b0 = b0[l], o.db = db[l];
      o.t_end = t_end[l];
      o.inv[0] = invx[l], o.inv[1] = invy[l];
      o.nudge[0] = nudgex[l], o.nudge[1] = nudgey[l];
    }
  }
}

}  // namespace glint::cpu
