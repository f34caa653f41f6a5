#include "glint/projection.h"

#include <cmath>

#include "glint/errors.h"

namespace glint {
namespace {

double det3(const Mat4& a, int r0, int r1, int r2, int c0, int c1, int c2) {
  return a(r0, c0) * (a(r1, c1) * a(r2, c2) - a(r1, c2) * a(r2, c1)) -
         a(r0, c1) * (a(r1, c0) * a(r2, c2) - a(r1, c2) * a(r2, c0)) +
         a(r0, c2) * (a(r1, c0) * a(r2, c1) - a(r1, c1) * a(r2, c0));
}

double det4(const Mat4& a) {
  double d = 0.0;
  for (int c = 0; c < 4; ++c) {
    int cols[3], k = 0;
    for (int j = 0; j < 4; ++j)
      if (j != c) cols[k++] = j;
    double minor = det3(a, 1, 2, 3, cols[0], cols[1], cols[2]);
    d += ((c % 2) ? -1.0 : 1.0) * a(0, c) * minor;
  }
  return d;
}

}  // namespace

void validate_projection(const Mat4& p) {
  double scale = 0.0;
  for (double v : p.m) {
    if (!std::isfinite(v)) throw InvalidArgument("projection", "expected finite values, got NaN or Inf");
    scale = std::fmax(scale, std::fabs(v));
  }
  // Singular relative to the matrix's own scale, so a 1e-4 / 1e7 near/far
  // pair (entries spanning eleven orders of magnitude) still passes.
  const double d = det4(p);
  if (scale == 0.0 || !(std::fabs(d) > 1e-300) ||
      std::fabs(d) < 1e-30 * scale * scale * scale * scale) {
    throw InvalidArgument("projection", "expected an invertible 4x4 matrix, got a singular one");
  }
}

Mat4 inverse(const Mat4& a) {
  // Adjugate over the determinant: a 4x4 needs nothing cleverer, and double
  // keeps a 1e-4 / 1e7 near/far pair's digits.
  const double d = det4(a);
  Mat4 inv;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      int rows[3], cols[3], kr = 0, kc = 0;
      for (int i = 0; i < 4; ++i) {
        if (i != c) rows[kr++] = i;  // transposed: cofactor of (c, r)
        if (i != r) cols[kc++] = i;
      }
      const double minor = det3(a, rows[0], rows[1], rows[2], cols[0], cols[1], cols[2]);
      inv(r, c) = ((r + c) % 2 ? -minor : minor) / d;
    }
  }
  return inv;
}

ProjectionKind classify_projection(const Mat4& p) {
  if (p(3, 0) == 0.0 && p(3, 1) == 0.0 && p(3, 2) == -1.0 && p(3, 3) == 0.0)
    return ProjectionKind::Perspective;
  if (p(3, 0) == 0.0 && p(3, 1) == 0.0 && p(3, 2) == 0.0 && p(3, 3) == 1.0)
    return ProjectionKind::Orthographic;
  return ProjectionKind::General;
}

Mat4 perspective(double fov_y, double aspect, double near, double far) {
  Mat4 m;
  const double f = 1.0 / std::tan(fov_y * 0.5);
  m(0, 0) = f / aspect;
  m(1, 1) = f;
  m(2, 2) = -(far + near) / (far - near);
  m(2, 3) = -2.0 * far * near / (far - near);
  m(3, 2) = -1.0;
  return m;
}

Mat4 orthographic(double half_width, double half_height, double near, double far) {
  Mat4 m;
  m(0, 0) = 1.0 / half_width;
  m(1, 1) = 1.0 / half_height;
  m(2, 2) = -2.0 / (far - near);
  m(2, 3) = -(far + near) / (far - near);
  m(3, 3) = 1.0;
  return m;
}

}  // namespace glint
