// The split-sum table, shared by both backends (the GL one uploads it).
#include "glint/brdf.h"

#include <cmath>
#include <algorithm>
#include <cstdint>

#include "glint/schema.h"

namespace glint {
namespace {

// Smith's Lambda for GGX at a direction with cosine c to the normal.
double smith_lambda(double c, double a2) {
  const double t2 = (1.0 - c * c) / (c * c);
  return 0.5 * (-1.0 + std::sqrt(1.0 + a2 * t2));
}

// The exact (unpolarized) Fresnel reflectance of a dielectric of index n at a
// cosine c to the normal; total internal reflection cannot happen for n > 1.
double fresnel_dielectric(double c, double n) {
  const double g = std::sqrt(n * n - 1.0 + c * c);
  const double a = (g - c) / (g + c);
  const double b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
  return 0.5 * a * a * (1.0 + b * b);
}

// Fh: that reflectance rescaled to 0 head on and 1 at grazing, the part of
// F = F0 + (1 - F0) Fh that the table's B carries (schema.h, kFresnelShapeIor).
double fresnel_shape(double c) {
  const double n = kFresnelShapeIor;
  const double f0 = (n - 1.0) * (n - 1.0) / ((n + 1.0) * (n + 1.0));
  return (fresnel_dielectric(c, n) - f0) / (1.0 - f0);
}

// The integrals of one node over GGX half-vectors, in the variables that
// make D(h) (N.H) uniform: u = the CDF of the polar angle, phi the azimuth.
// In them each half-vector's share of f cos(l) / pdf(l) is
// G2 (V.H) / ((N.H) (N.V)). V lies in the x-z plane, so the integrand is even
// in phi, and for each u the mirrored direction l stays above the surface
// exactly for cos(phi) > c*, c* = (N.V / (2 N.H) - N.V N.H) / (|V_xy| sin):
// a midpoint grid over that phi range only (instead of [0, pi] with the
// cut-off inside a cell) keeps the grid error small at grazing N.V, where the
// cut-off sweeps across most of the lobe. The polar CDF is walked as
// u = 1 - (1 - s)^3 (Jacobian 3 (1 - s)^2) with s on a midpoint grid: the
// weights grow as 1 / N.H towards u = 1, and a plain grid in u converged
// there only as slowly as 0.02 at 128 steps, grazing; this one to 1e-4.
void integrate(double nov, double alpha, float* out) {
  const double pi = 3.14159265358979323846;
  const double a2 = alpha * alpha;
  const double vx = std::sqrt(1.0 - nov * nov), vz = nov;
  const double lambda_v = smith_lambda(nov, a2);
  double sa = 0.0, sb = 0.0;
  for (int i = 0; i < kEnvBrdfU; ++i) {
    const double s = (i + 0.5) / kEnvBrdfU, r = 1.0 - s;
    const double u = 1.0 - r * r * r, jacobian = 3.0 * r * r;
    const double cos_t = std::sqrt((1.0 - u) / (1.0 + (a2 - 1.0) * u));
    const double sin_t = std::sqrt(1.0 - cos_t * cos_t);
    const double num = vz / (2.0 * cos_t) - vz * cos_t, den = vx * sin_t;
    double phi_max = pi;
    if (den > 0.0) {
      const double c = num / den;
      if (c >= 1.0) continue;
      if (c > -1.0) phi_max = std::acos(c);
    } else if (num >= 0.0) {
      continue;
    }
    double ra = 0.0, rb = 0.0;
    for (int k = 0; k < kEnvBrdfPhi; ++k) {
      const double hx = sin_t * std::cos(phi_max * (k + 0.5) / kEnvBrdfPhi), hz = cos_t;
      const double voh = vx * hx + vz * hz;
      const double lz = 2.0 * voh * hz - vz;
      if (!(lz > 0.0) || !(voh > 0.0)) continue;
      const double g2 = 1.0 / (1.0 + lambda_v + smith_lambda(lz, a2));
      const double gv = g2 * voh / (hz * nov);
      const double fc = fresnel_shape(voh);
      ra += (1.0 - fc) * gv;
      rb += fc * gv;
    }
    sa += ra * (phi_max / pi) * jacobian;
    sb += rb * (phi_max / pi) * jacobian;
  }
  const double n = static_cast<double>(kEnvBrdfU) * kEnvBrdfPhi;
  out[0] = static_cast<float>(sa / n);
  out[1] = static_cast<float>(sb / n);
}

std::vector<float> build_table() {
  const int n = kEnvBrdfSize;
  std::vector<float> t(static_cast<size_t>(2 * n * n));
  for (int j = 0; j < n; ++j) {
    const double r = static_cast<double>(j) / (n - 1);
    for (int i = 0; i < n; ++i) {
      const double q = static_cast<double>(i) / (n - 1);
      const double nov = std::fmax(q * q, kEnvBrdfMinNdotV);
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
  env_brdf_lookup(env_brdf_table().data(), n_dot_v, alpha, a, b);
}

}  // namespace glint
