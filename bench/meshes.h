// Meshes the benchmarks rasterize, shared so that the CPU-only and the
// CPU-vs-GL figures are measured on the same geometry.
#pragma once
#include <algorithm>
#include <cmath>

#include "glint/raster.h"

namespace glint::bench {

// A wavy height field seen from above at an angle, floor level `base` in view
// y: n x n cells, two triangles each (~`triangles` in all), alternating
// materials 0 and 1 by triangle.
inline Mesh height_field(long triangles, double base = -2.0) {
  const int n = std::max(1, static_cast<int>(std::lround(std::sqrt(triangles / 2.0))));
  Mesh m;
  auto vertex = [&](int i, int j, float* p, float* nrm) {
    const double x = -8.0 + 16.0 * i / n, z = -2.0 - 14.0 * j / n;
    const double y = base + 0.3 * std::sin(1.7 * x) * std::cos(1.3 * z);
    const double dx = 0.3 * 1.7 * std::cos(1.7 * x) * std::cos(1.3 * z);
    const double dz = -0.3 * 1.3 * std::sin(1.7 * x) * std::sin(1.3 * z);
    const double len = std::sqrt(dx * dx + 1.0 + dz * dz);
    p[0] = float(x), p[1] = float(y), p[2] = float(z);
    nrm[0] = float(-dx / len), nrm[1] = float(1.0 / len), nrm[2] = float(-dz / len);
  };
  auto push = [&](int i, int j) {
    float p[3], nrm[3];
    vertex(i, j, p, nrm);
    m.positions.insert(m.positions.end(), p, p + 3);
    m.normals.insert(m.normals.end(), nrm, nrm + 3);
  };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      push(i, j), push(i + 1, j), push(i + 1, j + 1);
      push(i, j), push(i + 1, j + 1), push(i, j + 1);
      m.material.push_back(0);
      m.material.push_back(1);
    }
  return m;
}

}  // namespace glint::bench
