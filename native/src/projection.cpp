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

CameraEye camera_eye(const Mat4& P) {
  CameraEye out;
  EyeKind& kind = out.kind;
  float* eye = out.eye;
  // Null vector of the 3x4 matrix of rows 0, 1, 3, by cofactors.
  const int rows[3] = {0, 1, 3};
  double e[4];
  for (int c = 0; c < 4; ++c) {
    int cols[3], k = 0;
    for (int j = 0; j < 4; ++j)
      if (j != c) cols[k++] = j;
    auto m = [&](int r, int cc) { return P(rows[r], cols[cc]); };
    const double minor = m(0, 0) * (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1)) -
                         m(0, 1) * (m(1, 0) * m(2, 2) - m(1, 2) * m(2, 0)) +
                         m(0, 2) * (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0));
    e[c] = (c % 2 ? -1.0 : 1.0) * minor;
  }
  const double len = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2] + e[3] * e[3]);
  if (classify_projection(P) == ProjectionKind::Perspective || len == 0.0) {
    kind = EyeKind::Origin;
    eye[0] = eye[1] = eye[2] = 0.0f;
    return out;
  }
  if (std::fabs(e[3]) > 1e-12 * len) {
    kind = EyeKind::Point;
    for (int i = 0; i < 3; ++i) eye[i] = static_cast<float>(e[i] / e[3]);
    return out;
  }
  // An eye at infinity: the rays run along e. Point them into the scene, the
  // way normalized device depth grows (OpenGL: near -1, far +1).
  const double dz = P(2, 0) * e[0] + P(2, 1) * e[1] + P(2, 2) * e[2];
  const double sign = dz >= 0.0 ? 1.0 : -1.0;
  const double dl = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
  kind = EyeKind::Direction;
  for (int i = 0; i < 3; ++i) eye[i] = static_cast<float>(sign * e[i] / dl);
  return out;
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
