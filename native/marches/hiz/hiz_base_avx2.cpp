// The pyramid's base level (march_hiz.cpp's base_range()) for x86-64 CPUs
// with AVX2: eight texels of a row at once, one per lane. Like
// hiz_walk_avx2.cpp, this file alone is built with -mavx2 and not -mfma, and
// includes no inline functions but hiz_lanes_avx2.h's, which are private to
// it, so that no AVX2 copy of a shared function reaches the linker. Each lane
// does base_range()'s float operations in its order (the min and max
// operands placed so that ties pick what std::min and std::max pick), so the
// base is the scalar one bit for bit; the tests hold the two traces equal.
//
// Why: the base is a division and four corner divisions per texel, each
// waiting on the one before in the scalar loop; at 1920x1080 the base took
// a tenth of a balanced trace on the CPU.
#include <immintrin.h>

#include "hiz_base.h"
#include "hiz_lanes_avx2.h"

namespace glint::cpu {
namespace {

// (a < b) ? a : b and (a > b) ? a : b, as minps and maxps define them.
__attribute__((always_inline)) inline VF vmin(VF a, VF b) {
  return reinterpret_cast<VF>(_mm256_min_ps(reinterpret_cast<__m256>(a), reinterpret_cast<__m256>(b)));
}
__attribute__((always_inline)) inline VF vmax(VF a, VF b) {
  return reinterpret_cast<VF>(_mm256_max_ps(reinterpret_cast<__m256>(a), reinterpret_cast<__m256>(b)));
}

}  // namespace

int hiz_base_row_avx2(const BaseRow& a) {
  const float* H = a.inv;
  const float w = static_cast<float>(a.width), h = static_cast<float>(a.height);
  const float sxs = 2.0f / w, sys = 2.0f / h;
  const float sy0s = static_cast<float>(a.y) * sys - 1.0f, sy1s = static_cast<float>(a.y + 1) * sys - 1.0f;
  const VF sy0 = splat(sy0s), sy1 = splat(sy1s), inf = splat(__builtin_inff()), zero = splat(0.0f);
  const int full = a.width - a.width % 8;
  for (int x0 = 0; x0 < full; x0 += 8) {
    // The lanes' inputs, one vector per channel: the RGBA rows by two 4x4
    // transposes, the plane normals' xyz by the same transposes on 4-float
    // loads whose fourth float is not used (masked, so that the image's last
    // texel reads nothing past its buffer).
    VF p[4], n[4], b[4];
    load_channels(a.position, x0, p);
    load_xyz_channels(a.planes, x0, n);
    if (a.back) load_channels(a.back, x0, b);
    const VI seen = seen_mask(a.seen, x0);
    const VI xs = VI{0, 1, 2, 3, 4, 5, 6, 7} + x0;
    const VF sx0 = __builtin_convertvector(xs, VF) * sxs - 1.0f;
    const VF sx1 = __builtin_convertvector(xs + 1, VF) * sxs - 1.0f;
    const VF d = -p[2];
    // texel_thickness(): the back layer's where it is seen and behind.
    VF t = splat(a.thickness);
    if (a.back) {
      const VI back_seen = texel_seen(b);
      const VF kt = pick(back_seen & (-b[2] > d), -b[2] - d, splat(-1.0f));
      t = pick(kt > zero, kt, t);
    }
    // texel_plane(): a usable normal and a plane not seen edge-on.
    const VI usable = finite(n[0]) & finite(n[1]) & finite(n[2]) &
                      ((n[0] != zero) | (n[1] != zero) | (n[2] != zero));
    const VF k = n[0] * p[0] + n[1] * p[1] + n[2] * p[2];
    VF L[4];
    for (int c = 0; c < 4; ++c) L[c] = n[0] * H[c] + n[1] * H[4 + c] + n[2] * H[8 + c] - k * H[12 + c];
    const VI planed = usable & (L[2] != zero);
    VF lo = d, hi = d;
    if (_mm256_movemask_ps(reinterpret_cast<__m256>(planed & seen))) {
      const VF abs_d = reinterpret_cast<VF>(reinterpret_cast<VI>(d) & 0x7fffffff);  // std::fabs
      const VF spread = splat(a.footprint_spread) * abs_d + t;
      const VF r = splat(1.0f) / L[2];
      const VF al = -L[0] * r, be = -L[1] * r, ga = -L[3] * r;
      const VF nx = H[8] + H[10] * al, ny = H[9] + H[10] * be, nc = H[11] + H[10] * ga;
      const VF dx = H[12] + H[14] * al, dy = H[13] + H[14] * be, dc = H[15] + H[14] * ga;
      const VF near = d - spread, far = d + spread;
      const VF sx[4] = {sx0, sx1, sx0, sx1}, sy[4] = {sy0, sy0, sy1, sy1};
      VF plo = d, phi = d;
      for (int corner = 0; corner < 4; ++corner) {
        const VF cd = -((nx * sx[corner] + ny * sy[corner] + nc) / (dx * sx[corner] + dy * sy[corner] + dc));
        const VF clamped = vmin(far, vmax(near, cd));  // std::min(std::max(cd, near), far)
        const VI ok = finite(cd);
        plo = pick(ok, vmin(clamped, plo), plo);  // std::min(lo, cd)
        phi = pick(ok, vmax(clamped, phi), phi);  // std::max(hi, cd)
      }
      lo = pick(planed, plo, d);
      hi = pick(planed, phi, d);
    }
    lo = pick(seen, lo, inf);
    hi = pick(seen, hi + t, -inf);
    // (lo, hi) pairs in texel order: the unpacks interleave within each
    // 128-bit half, the permutes put the halves in order.
    const __m256 u0 = _mm256_unpacklo_ps(reinterpret_cast<__m256>(lo), reinterpret_cast<__m256>(hi));
    const __m256 u1 = _mm256_unpackhi_ps(reinterpret_cast<__m256>(lo), reinterpret_cast<__m256>(hi));
    float* o = a.out + static_cast<size_t>(x0) * 2;
    _mm256_storeu_ps(o, _mm256_permute2f128_ps(u0, u1, 0x20));
    _mm256_storeu_ps(o + 8, _mm256_permute2f128_ps(u0, u1, 0x31));
  }
  return full;
}

}  // namespace glint::cpu
