// The split-sum table, shared by both backends (the GL one uploads it).
#include "glint/brdf.h"

#include <cmath>
#include <algorithm>
#include <cstdint>

namespace glint {
namespace {

double radical_inverse(uint32_t bits) {
  bits = (bits << 16u) | (bits >> 16u);
  bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
  bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
  bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
  bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
  return static_cast<double>(bits) * 2.3283064365386963e-10;
}

// Smith's Lambda for GGX at a direction with cosine c to the normal.
double smith_lambda(double c, double a2) {
  const double t2 = (1.0 - c * c) / (c * c);
  return 0.5 * (-1.0 + std::sqrt(1.0 + a2 * t2));
}

// The integrals of one node: GGX half-vectors drawn with pdf D(h) (N.H), so
// each sample's estimate of f cos(l) / pdf(l) is G2 (V.H) / ((N.H) (N.V)).
void integrate(double nov, double alpha, float* out) {
  const double a2 = alpha * alpha;
  const double vx = std::sqrt(1.0 - nov * nov), vz = nov;
  const double pi = 3.14159265358979323846;
  double sa = 0.0, sb = 0.0;
  for (int k = 0; k < kEnvBrdfSamples; ++k) {
    const double u1 = (k + 0.5) / kEnvBrdfSamples, u2 = radical_inverse(static_cast<uint32_t>(k));
    const double phi = 2.0 * pi * u2;
    const double cos_t = std::sqrt((1.0 - u1) / (1.0 + (a2 - 1.0) * u1));
    const double sin_t = std::sqrt(1.0 - cos_t * cos_t);
    const double hx = sin_t * std::cos(phi), hz = cos_t;
    const double voh = vx * hx + vz * hz;
    const double lz = 2.0 * voh * hz - vz;
    if (!(lz > 0.0) || !(voh > 0.0)) continue;
    const double g2 = 1.0 / (1.0 + smith_lambda(nov, a2) + smith_lambda(lz, a2));
    const double gv = g2 * voh / (hz * nov);
    const double fc = std::pow(1.0 - voh, 5.0);
    sa += (1.0 - fc) * gv;
    sb += fc * gv;
  }
  out[0] = static_cast<float>(sa / kEnvBrdfSamples);
  out[1] = static_cast<float>(sb / kEnvBrdfSamples);
}

std::vector<float> build_table() {
  const int n = kEnvBrdfSize;
  std::vector<float> t(static_cast<size_t>(2 * n * n));
  for (int j = 0; j < n; ++j) {
    const double r = static_cast<double>(j) / (n - 1);
    for (int i = 0; i < n; ++i) {
      const double nov = std::fmax(static_cast<double>(i) / (n - 1), kEnvBrdfMinNdotV);
      integrate(nov, r * r, &t[2 * (j * n + i)]);
    }
  }
  return t;
}

}  // namespace

const std::vector<float>& env_brdf_table() {
  static const std::vector<float> table = build_table();
  return table;
}

void env_brdf(float n_dot_v, float alpha, float* a, float* b) {
  const std::vector<float>& t = env_brdf_table();
  const int n = kEnvBrdfSize;
  const float scale = static_cast<float>(n - 1);
  auto clamp01 = [](float v) { return v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f; };
  const float x = clamp01(n_dot_v) * scale;
  const float y = std::sqrt(clamp01(alpha)) * scale;
  const int x0 = std::min(static_cast<int>(x), n - 2), y0 = std::min(static_cast<int>(y), n - 2);
  const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
  for (int c = 0; c < 2; ++c) {
    const float v00 = t[2 * (y0 * n + x0) + c], v10 = t[2 * (y0 * n + x0 + 1) + c];
    const float v01 = t[2 * ((y0 + 1) * n + x0) + c], v11 = t[2 * ((y0 + 1) * n + x0 + 1) + c];
    const float bottom = v00 * (1.0f - fx) + v10 * fx;
    const float top = v01 * (1.0f - fx) + v11 * fx;
    (c == 0 ? *a : *b) = bottom * (1.0f - fy) + top * fy;
  }
}

}  // namespace glint
