// Exact G-buffers for tests and benchmarks: a few analytic shapes ray-cast
// through every pixel centre of a perspective or orthographic camera.
#pragma once
#include <cmath>
#include <vector>

#include "glint/image.h"
#include "glint/projection.h"

namespace glint::test {

struct Sphere {
  double c[3];
  double r;
  float color[3];
  float specular;   // specular amount (grey)
  float shininess;  // specular-buffer alpha in [0, 1]
};
struct Plane {  // points p with dot(n, p) = d
  double n[3];
  double d;
  float color[3];
  float specular;
  float shininess;
};

struct Scene {
  std::vector<Sphere> spheres;
  std::vector<Plane> planes;
};

struct GBuffer {
  Image position, normal, specular, color;
  Mat4 projection;
};

// The view ray through pixel (x, y): origin and direction in view space.
inline void pixel_ray(const Mat4& p, bool ortho, int x, int y, int w, int h, double o[3], double d[3]) {
  const double nx = (x + 0.5) / w * 2.0 - 1.0, ny = (y + 0.5) / h * 2.0 - 1.0;
  if (!ortho) {
    o[0] = o[1] = o[2] = 0.0;
    // x_ndc = (p00 x + p02 z) / -z etc.; on the plane z = -1:
    // At z = -1, clip.w = 1 and ndc.x = p00 x + p02 z, so x = (ndc.x + p02) / p00.
    d[0] = (nx + p(0, 2)) / p(0, 0);
    d[1] = (ny + p(1, 2)) / p(1, 1);
    d[2] = -1.0;
  } else {
    o[0] = (nx - p(0, 3)) / p(0, 0);
    o[1] = (ny - p(1, 3)) / p(1, 1);
    o[2] = 0.0;
    d[0] = d[1] = 0.0;
    d[2] = -1.0;
  }
}

inline GBuffer render(const Scene& s, const Mat4& proj, int w, int h, const float background[3] = nullptr) {
  GBuffer g{Image(w, h), Image(w, h), Image(w, h), Image(w, h), proj};
  const bool ortho = classify_projection(proj) == ProjectionKind::Orthographic;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double o[3], d[3];
      pixel_ray(proj, ortho, x, y, w, h, o, d);
      double best = 1e300, n[3] = {0, 0, 0};
      const float* col = nullptr;
      float spec = 0, shin = 0;
      for (const auto& sp : s.spheres) {
        const double oc[3] = {o[0] - sp.c[0], o[1] - sp.c[1], o[2] - sp.c[2]};
        const double a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        const double b = 2 * (oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2]);
        const double c = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - sp.r * sp.r;
        const double disc = b * b - 4 * a * c;
        if (disc < 0) continue;
        const double t = (-b - std::sqrt(disc)) / (2 * a);
        if (t > 1e-9 && t < best) {
          best = t;
          for (int k = 0; k < 3; ++k) n[k] = (o[k] + d[k] * t - sp.c[k]) / sp.r;
          col = sp.color;
          spec = sp.specular;
          shin = sp.shininess;
        }
      }
      for (const auto& pl : s.planes) {
        const double dn = pl.n[0] * d[0] + pl.n[1] * d[1] + pl.n[2] * d[2];
        if (std::fabs(dn) < 1e-12) continue;
        const double t = (pl.d - (pl.n[0] * o[0] + pl.n[1] * o[1] + pl.n[2] * o[2])) / dn;
        if (t > 1e-9 && t < best) {
          best = t;
          for (int k = 0; k < 3; ++k) n[k] = pl.n[k];
          col = pl.color;
          spec = pl.specular;
          shin = pl.shininess;
        }
      }
      float* P = g.position.px(x, y);
      float* N = g.normal.px(x, y);
      float* S = g.specular.px(x, y);
      float* C = g.color.px(x, y);
      if (!col) {
        for (int k = 0; k < 3; ++k) C[k] = background ? background[k] : 0.0f;
        C[3] = 1.0f;
        continue;
      }
      for (int k = 0; k < 3; ++k) {
        P[k] = static_cast<float>(o[k] + d[k] * best);
        N[k] = static_cast<float>(n[k]);
        S[k] = spec;
        C[k] = col[k];
      }
      P[3] = 1.0f;
      S[3] = shin;
      C[3] = 1.0f;
    }
  }
  return g;
}

// A mirror floor under a red sphere in front of a blue wall: the scene the
// tests and benchmarks share.
inline Scene mirror_floor_scene() {
  Scene s;
  s.planes.push_back({{0, 1, 0}, -1.0, {0.5f, 0.5f, 0.5f}, 1.0f, 1.0f});   // floor y = -1
  s.planes.push_back({{0, 0, 1}, -12.0, {0.1f, 0.2f, 0.9f}, 0.0f, 0.0f});  // wall z = -12
  s.spheres.push_back({{0.0, 0.0, -6.0}, 1.0, {0.9f, 0.1f, 0.1f}, 0.0f, 0.0f});
  s.spheres.push_back({{2.2, -0.4, -7.0}, 0.6, {0.1f, 0.9f, 0.1f}, 0.5f, 0.4f});
  return s;
}

}  // namespace glint::test
