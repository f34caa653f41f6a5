// The CPU rasterizer against hand-counted coverage, analytic ray casts and a
// brute-force ray/triangle reference written out here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "cpu/raster.h"
#include "glint/errors.h"
#include "glint/raster.h"
#include "glint/stages.h"

using namespace glint;

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Tri {
  double p[3][3];
  double n[3][3];
  int material = 0;
  double uv[3][2] = {{0, 0}, {0, 0}, {0, 0}};
  double t[3][4] = {{1, 0, 0, 1}, {1, 0, 0, 1}, {1, 0, 0, 1}};
};

// A triangle with one normal on every corner.
Tri flat(const double a[3], const double b[3], const double c[3], const double n[3], int mat = 0) {
  Tri t;
  for (int k = 0; k < 3; ++k) {
    t.p[0][k] = a[k], t.p[1][k] = b[k], t.p[2][k] = c[k];
    for (int v = 0; v < 3; ++v) t.n[v][k] = n[k];
  }
  t.material = mat;
  return t;
}

Mesh make_mesh(const std::vector<Tri>& tris, bool with_tangents = false) {
  Mesh m;
  for (const Tri& t : tris) {
    for (int v = 0; v < 3; ++v) {
      for (int k = 0; k < 3; ++k) {
        m.positions.push_back(static_cast<float>(t.p[v][k]));
        m.normals.push_back(static_cast<float>(t.n[v][k]));
      }
      if (with_tangents) {
        m.uvs.push_back(static_cast<float>(t.uv[v][0]));
        m.uvs.push_back(static_cast<float>(t.uv[v][1]));
        for (int k = 0; k < 4; ++k) m.tangents.push_back(static_cast<float>(t.t[v][k]));
      }
    }
    m.material.push_back(t.material);
  }
  return m;
}

std::vector<Material> default_materials() {
  Material a;
  a.specular[0] = 0.25f, a.specular[1] = 0.5f, a.specular[2] = 0.75f;
  a.shininess = 63.875f;  // half of 127.75
  Material b;
  b.specular[0] = b.specular[1] = b.specular[2] = 1.0f;
  b.shininess = 127.75f;
  return {a, b};
}

GBufferImages run(const std::vector<Tri>& tris, const Mat4& proj, int w, int h,
                  const std::vector<Material>& mats = default_materials(),
                  const std::vector<Image>& maps = {}, int threads = 2) {
  const Mesh mesh = make_mesh(tris, !maps.empty());
  return cpu::rasterize(RasterInputs{mesh, mats, maps, proj, w, h}, threads);
}

// A 90-degree square perspective: x_ndc = x / -z exactly (m00 = m11 = 1).
Mat4 square_perspective(double near = 0.1, double far = 100.0) {
  Mat4 p = perspective(kPi / 2, 1.0, near, far);
  p(0, 0) = 1.0;
  p(1, 1) = 1.0;
  return p;
}

// Orthographic with one view unit per pixel on a w x h image: screen x = x + w / 2.
Mat4 pixel_ortho(int w, int h) { return orthographic(w / 2.0, h / 2.0, 0.1, 100.0); }

int covered(const Image& pos) {
  int n = 0;
  for (int y = 0; y < pos.height; ++y)
    for (int x = 0; x < pos.width; ++x) n += pos.px(x, y)[3] == 1.0f;
  return n;
}

// An axis-aligned quad at depth z (two triangles, diagonal a-c), front-facing
// (counter-clockwise from the camera) unless `reversed`.
std::vector<Tri> quad(double x0, double y0, double x1, double y1, double z, bool reversed = false,
                      int mat = 0) {
  const double a[3] = {x0, y0, z}, b[3] = {x1, y0, z}, c[3] = {x1, y1, z}, d[3] = {x0, y1, z};
  const double n[3] = {0, 0, reversed ? -1.0 : 1.0};
  if (reversed) return {flat(a, c, b, n, mat), flat(a, d, c, n, mat)};
  return {flat(a, b, c, n, mat), flat(a, c, d, n, mat)};
}

// A closed axis-aligned box, every face wound counter-clockwise seen from
// outside (so its far side is back-facing from any eye outside it).
std::vector<Tri> box(const double lo[3], const double hi[3], int mat) {
  std::vector<Tri> tris;
  for (int a = 0; a < 3; ++a)
    for (int side = 0; side < 2; ++side) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      double q[4][3];
      const double bc[4][2] = {{lo[b], lo[c]}, {hi[b], lo[c]}, {hi[b], hi[c]}, {lo[b], hi[c]}};
      for (int k = 0; k < 4; ++k) {
        // e_b x e_c = e_a: this order faces +a; the -a face walks it backwards.
        const int from = side ? k : 3 - k;
        q[k][a] = side ? hi[a] : lo[a];
        q[k][b] = bc[from][0];
        q[k][c] = bc[from][1];
      }
      double n[3] = {0, 0, 0};
      n[a] = side ? 1.0 : -1.0;
      tris.push_back(flat(q[0], q[1], q[2], n, mat));
      tris.push_back(flat(q[0], q[2], q[3], n, mat));
    }
  return tris;
}

void expect_rect(const Image& pos, int i0, int i1, int j0, int j1) {
  for (int y = 0; y < pos.height; ++y)
    for (int x = 0; x < pos.width; ++x) {
      const bool inside = x >= i0 && x <= i1 && y >= j0 && y <= j1;
      ASSERT_EQ(pos.px(x, y)[3], inside ? 1.0f : 0.0f) << "pixel " << x << ", " << y;
    }
}

}  // namespace

// Unit quad at z = -2 under a 90-degree camera on 64 x 64: the view spans
// [-2, 2] there, 16 pixels per unit, so x in [-0.5, 0.5] lands on screen
// columns [24, 40]: centres 24.5 .. 39.5, 16 x 16 = 256 pixels.
TEST(Raster, UnitQuadCoversTheHandCountedRectangle) {
  const auto g = run(quad(-0.5, -0.5, 0.5, 0.5, -2.0), square_perspective(), 64, 64);
  EXPECT_EQ(covered(g.position), 256);
  expect_rect(g.position, 24, 39, 24, 39);
}

TEST(Raster, PositionsAreThePixelRaysHitOnThePlane) {
  const int w = 64, h = 48;
  Mat4 p = perspective(0.8, double(w) / h, 0.1, 100.0);
  // A tilted plane through (0, 0, -3) with normal m; two big triangles on it.
  const double m[3] = {0.3, 0.4, std::sqrt(1 - 0.25)};
  auto on_plane = [&](double x, double y, double out[3]) {
    out[0] = x, out[1] = y;
    out[2] = -3.0 - (m[0] * x + m[1] * y) / m[2];
  };
  double a[3], b[3], c[3], d[3];
  on_plane(-3, -3, a), on_plane(3, -3, b), on_plane(3, 3, c), on_plane(-3, 3, d);
  const auto g = run({flat(a, b, c, m), flat(a, c, d, m)}, p, w, h);
  int checked = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float* q = g.position.px(x, y);
      ASSERT_EQ(q[3], 1.0f);  // the plane fills the view
      // Ray (ndc.x / p00, ndc.y / p11, -1) from the eye meets dot(m, r t) = dot(m, (0, 0, -3)).
      const double rx = ((x + 0.5) / w * 2 - 1) / p(0, 0), ry = ((y + 0.5) / h * 2 - 1) / p(1, 1);
      const double t = (-3.0 * m[2]) / (m[0] * rx + m[1] * ry - m[2]);
      const double e[3] = {rx * t, ry * t, -t};
      for (int k = 0; k < 3; ++k)
        ASSERT_NEAR(q[k], e[k], 1e-5 * std::fabs(e[2])) << x << "," << y << " axis " << k;
      const float* n = g.normal.px(x, y);
      for (int k = 0; k < 3; ++k) ASSERT_NEAR(n[k], m[k], 1e-6);
      ASSERT_EQ(n[3], 1.0f);
      const float* s = g.specular.px(x, y);
      EXPECT_EQ(s[0], 0.25f);
      EXPECT_EQ(s[1], 0.5f);
      EXPECT_EQ(s[2], 0.75f);
      EXPECT_FLOAT_EQ(s[3], 0.5f);
      ++checked;
    }
  EXPECT_EQ(checked, w * h);
}

TEST(Raster, UnseenPixelsAreAllZeros) {
  const auto g = run(quad(-0.5, -0.5, 0.5, 0.5, -2.0), square_perspective(), 64, 64);
  for (const Image* img : {&g.position, &g.normal, &g.specular})
    for (int c = 0; c < 4; ++c) EXPECT_EQ(img->px(0, 0)[c], 0.0f);
}

// Edges exactly on pixel centres (screen 24.5 .. 40.5 both ways): the left
// column and row 24 are in, the right column and row 40 are out (the
// top-left rule in row-index order: row 24 is the "top", the smaller index);
// the shared diagonal runs through centres too.
TEST(Raster, TopLeftRuleOnCentresExactlyOnEdges) {
  const int w = 64, h = 64;
  for (bool reversed : {false, true}) {
    const auto tris = quad(24.5 - 32, 24.5 - 32, 40.5 - 32, 40.5 - 32, -2.0, reversed);
    const auto g = run(tris, pixel_ortho(w, h), w, h);
    expect_rect(g.position, 24, 39, 24, 39);
    std::vector<float> pos;
    for (const Tri& t : tris)
      for (int v = 0; v < 3; ++v)
        for (int k = 0; k < 3; ++k) pos.push_back(static_cast<float>(t.p[v][k]));
    const auto counts = cpu::coverage_count(pos, pixel_ortho(w, h), w, h);
    EXPECT_EQ(*std::max_element(counts.begin(), counts.end()), 1);
  }
  // The same on a quad wide enough that rows are solved per edge rather
  // than scanned pixel by pixel: columns 4..59, rows 4..59.
  const auto wide = run(quad(4.5 - 32, 4.5 - 32, 60.5 - 32, 60.5 - 32, -2.0), pixel_ortho(w, h), w, h);
  expect_rect(wide.position, 4, 59, 4, 59);
  const auto wide_tri = run({quad(4.5 - 32, 4.5 - 32, 60.5 - 32, 60.5 - 32, -2.0)[0]}, pixel_ortho(w, h), w, h);
  EXPECT_EQ(covered(wide_tri.position), 56 * 57 / 2);  // lower-right half with its diagonal (a left edge)
}

// A jittered grid mesh over the square [24.5, 40.5]^2 (boundary fixed):
// every centre inside is covered exactly once, whatever the inner edges.
TEST(Raster, SharedEdgesAreCoveredExactlyOnce) {
  const int w = 64, h = 64, cells = 8;
  std::mt19937 rng(3);
  for (int round = 0; round < 4; ++round) {
    // Round 0 puts inner vertices on pixel centres (ties everywhere),
    // later rounds jitter them off the grid.
    std::uniform_real_distribution<double> jitter(-0.3, 0.3);  // small enough that no triangle folds over
    double vx[cells + 1][cells + 1], vy[cells + 1][cells + 1];
    for (int a = 0; a <= cells; ++a)
      for (int b = 0; b <= cells; ++b) {
        vx[a][b] = 24.5 + 2.0 * a;
        vy[a][b] = 24.5 + 2.0 * b;
        if (round > 0 && a > 0 && a < cells && b > 0 && b < cells) {
          vx[a][b] += jitter(rng);
          vy[a][b] += jitter(rng);
        }
      }
    std::vector<float> pos;
    auto corner = [&](int a, int b) {
      pos.push_back(static_cast<float>(vx[a][b] - 32));
      pos.push_back(static_cast<float>(vy[a][b] - 32));
      pos.push_back(-2.0f);
    };
    for (int a = 0; a < cells; ++a)
      for (int b = 0; b < cells; ++b) {
        const bool flip = (a + b + round) % 2;  // both diagonals and both windings
        corner(a, b), corner(a + 1, b), corner(flip ? a : a + 1, b + 1);
        if (flip) corner(a + 1, b), corner(a + 1, b + 1), corner(a, b + 1);
        else corner(a, b), corner(a, b + 1), corner(a + 1, b + 1);
      }
    const auto counts = cpu::coverage_count(pos, pixel_ortho(w, h), w, h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const bool inside = x >= 24 && x <= 39 && y >= 24 && y <= 39;
        ASSERT_EQ(counts[y * w + x], inside ? 1 : 0) << "round " << round << " pixel " << x << "," << y;
      }
  }
}

// A UV sphere inscribed in the analytic one: every seen point lies between
// the sphere and the tessellation's inner bound, normals are unit, outward
// and facing the eye, and the silhouette matches the analytic disc.
TEST(Raster, SphereMeshMatchesTheAnalyticSphere) {
  const int w = 96, h = 80, lon = 64, lat = 32;
  const double c[3] = {0.4, -0.2, -5.0}, r = 1.5;
  const Mat4 p = perspective(0.9, double(w) / h, 0.1, 100.0);
  auto vertex = [&](int i, int j, double pos[3], double nrm[3]) {
    const double th = kPi * j / lat, ph = 2 * kPi * i / lon;
    nrm[0] = std::sin(th) * std::cos(ph), nrm[1] = std::cos(th), nrm[2] = std::sin(th) * std::sin(ph);
    for (int k = 0; k < 3; ++k) pos[k] = c[k] + r * nrm[k];
  };
  std::vector<Tri> tris;
  for (int j = 0; j < lat; ++j)
    for (int i = 0; i < lon; ++i) {
      Tri a, b;
      vertex(i, j, a.p[0], a.n[0]), vertex(i + 1, j, a.p[1], a.n[1]), vertex(i + 1, j + 1, a.p[2], a.n[2]);
      vertex(i, j, b.p[0], b.n[0]), vertex(i + 1, j + 1, b.p[1], b.n[1]), vertex(i, j + 1, b.p[2], b.n[2]);
      tris.push_back(a), tris.push_back(b);
    }
  const auto g = run(tris, p, w, h);
  // Largest gap between a flat facet and the sphere: half the facet's
  // angular diagonal, (pi / lat) * sqrt(2) / 2, as r (1 - cos).
  const double sag = r * (1 - std::cos(kPi / lat * std::sqrt(2.0) / 2 * 1.01));
  int seen = 0, analytic = 0, mismatched = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double d[3] = {((x + 0.5) / w * 2 - 1) / p(0, 0), ((y + 0.5) / h * 2 - 1) / p(1, 1), -1.0};
      const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
      const double dc = d[0] * c[0] + d[1] * c[1] + d[2] * c[2];
      const double disc = dc * dc - dd * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2] - r * r);
      const bool hit = disc >= 0;
      analytic += hit;
      const float* q = g.position.px(x, y);
      if (q[3] != 1.0f) {
        mismatched += hit;
        continue;
      }
      ++seen;
      mismatched += !hit;
      double rel[3], dist2 = 0;
      for (int k = 0; k < 3; ++k) rel[k] = q[k] - c[k], dist2 += rel[k] * rel[k];
      const double dist = std::sqrt(dist2);
      ASSERT_LE(dist, r + 1e-5);
      ASSERT_GE(dist, r - sag);
      const float* n = g.normal.px(x, y);
      const double len = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
      ASSERT_NEAR(len, 1.0, 1e-6);
      ASSERT_GT((n[0] * rel[0] + n[1] * rel[1] + n[2] * rel[2]) / dist, 0.99);
      ASSERT_LT(n[0] * q[0] + n[1] * q[1] + n[2] * q[2], 0.0);  // faces the eye
    }
  EXPECT_GT(analytic, 1000);
  // Only silhouette pixels may differ (the facets cut inside the sphere).
  EXPECT_LT(mismatched, analytic / 20);
  EXPECT_LE(seen, analytic);
}

// Floor y = -1 from behind the camera (z = +5) to z = -20: the part in
// front of the near plane is drawn, exactly where the pixel rays hit it.
TEST(Raster, TriangleCrossingTheNearPlaneMatchesRayCast) {
  const int w = 80, h = 60;
  const double near = 0.5;
  const Mat4 p = perspective(1.2, double(w) / h, near, 50.0);
  const double a[3] = {-30, -1, 5}, b[3] = {30, -1, 5}, c2[3] = {0, -1, -20}, up[3] = {0, 1, 0};
  // Winding a, b, c2 seen from above is counter-clockwise: the floor is front-facing.
  const auto g = run({flat(a, b, c2, up)}, p, w, h);
  int hits = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double d[3] = {((x + 0.5) / w * 2 - 1) / p(0, 0), ((y + 0.5) / h * 2 - 1) / p(1, 1), -1.0};
      const float* q = g.position.px(x, y);
      bool hit = false, margin = false;
      double e[3] = {0, 0, 0};
      if (d[1] < 0) {
        const double t = -1.0 / d[1];
        for (int k = 0; k < 3; ++k) e[k] = d[k] * t;
        // 2D barycentrics in the xz plane.
        const double det = (b[0] - a[0]) * (c2[2] - a[2]) - (c2[0] - a[0]) * (b[2] - a[2]);
        const double l1 = ((e[0] - a[0]) * (c2[2] - a[2]) - (c2[0] - a[0]) * (e[2] - a[2])) / det;
        const double l2 = ((b[0] - a[0]) * (e[2] - a[2]) - (e[0] - a[0]) * (b[2] - a[2])) / det;
        const double l0 = 1 - l1 - l2;
        const double dist = -e[2];
        hit = l0 >= 0 && l1 >= 0 && l2 >= 0 && dist >= near && dist <= 50.0;
        margin = std::min({std::fabs(l0), std::fabs(l1), std::fabs(l2)}) < 1e-3 ||
                 std::fabs(dist - near) < 1e-3;
      }
      if (margin) continue;
      ASSERT_EQ(q[3] == 1.0f, hit) << x << "," << y;
      if (!hit) continue;
      ++hits;
      for (int k = 0; k < 3; ++k) ASSERT_NEAR(q[k], e[k], 1e-5 * std::fabs(e[2]) + 1e-6);
      ASSERT_NEAR(g.normal.px(x, y)[1], 1.0f, 1e-6);
    }
  EXPECT_GT(hits, w * h / 4);
}

TEST(Raster, TriangleBehindTheCameraIsNotDrawn) {
  const double a[3] = {-1, -1, 2}, b[3] = {1, -1, 2}, c[3] = {0, 1, 2}, n[3] = {0, 0, 1};
  // Also one straddling z = 0 whose visible part lies outside the near plane:
  // it must not wrap around through infinity onto the screen.
  const double d[3] = {-1, -1, 3}, e[3] = {1, -1, 3}, f[3] = {0, 1, -0.05};
  for (const auto& tris : {std::vector<Tri>{flat(a, b, c, n)}, std::vector<Tri>{flat(d, e, f, n)}}) {
    const auto g = run(tris, square_perspective(0.1, 10.0), 32, 32);
    EXPECT_EQ(covered(g.position), 0);
    for (float v : g.normal.data) EXPECT_EQ(v, 0.0f);
  }
}

TEST(Raster, NearerSurfaceWinsAndTiesKeepTheFirstTriangle) {
  const Mat4 p = square_perspective();
  auto near_q = quad(-0.5, -0.5, 0.5, 0.5, -2.0, false, 0);
  auto far_q = quad(-2.0, -2.0, 2.0, 2.0, -3.0, false, 1);
  for (bool near_first : {true, false}) {
    std::vector<Tri> tris = near_first ? near_q : far_q;
    const auto& rest = near_first ? far_q : near_q;
    tris.insert(tris.end(), rest.begin(), rest.end());
    const auto g = run(tris, p, 64, 64);
    EXPECT_FLOAT_EQ(g.position.px(32, 32)[2], -2.0f);
    EXPECT_EQ(g.specular.px(32, 32)[0], 0.25f);
    EXPECT_FLOAT_EQ(g.position.px(20, 20)[2], -3.0f);  // outside the near quad: the far one
  }
  // Same depth: the triangle submitted first keeps the pixel.
  for (int first : {0, 1}) {
    auto tris = quad(-0.5, -0.5, 0.5, 0.5, -2.0, false, first);
    auto other = quad(-0.5, -0.5, 0.5, 0.5, -2.0, false, 1 - first);
    tris.insert(tris.end(), other.begin(), other.end());
    const auto g = run(tris, p, 64, 64, default_materials(), {}, 3);
    EXPECT_EQ(g.specular.px(30, 30)[0], first == 0 ? 0.25f : 1.0f);
  }
}

// Back faces: a quad wound clockwise as seen from the eye, with normals
// pointing away, comes out with normals toward the eye; and a ceiling whose
// normals point up is seen from below with normals pointing down.
TEST(Raster, BackFacesGetTheirNormalsFlipped) {
  const Mat4 p = square_perspective();
  const auto front = run(quad(-0.5, -0.5, 0.5, 0.5, -2.0, false), p, 64, 64);
  const auto back = run(quad(-0.5, -0.5, 0.5, 0.5, -2.0, true), p, 64, 64);
  EXPECT_EQ(covered(front.position), covered(back.position));
  EXPECT_EQ(front.normal.px(32, 32)[2], 1.0f);
  EXPECT_EQ(back.normal.px(32, 32)[2], 1.0f);  // stored normal (0, 0, -1), flipped

  const double a[3] = {-5, 1, -1}, b[3] = {5, 1, -1}, c[3] = {0, 1, -20}, up[3] = {0, 1, 0};
  // a -> b -> c winds counter-clockwise seen from above (face normal +y), so
  // from our eye below the ceiling it is a back face.
  const auto g = run({flat(a, b, c, up)}, p, 64, 64);
  ASSERT_EQ(g.position.px(32, 50)[3], 1.0f);
  EXPECT_NEAR(g.normal.px(32, 50)[1], -1.0f, 1e-6);
}

TEST(Raster, NormalMaps) {
  const int w = 64, h = 64;
  const Mat4 p = pixel_ortho(w, h);
  // Quad on screen [24.5, 40.5]^2 with uv (0, 0) at its bottom-left, so
  // pixel 28 sits at u = 0.25 and pixel 36 at u = 0.75: texel centres of a
  // 2 x 2 map, where bilinear sampling returns the texel itself.
  auto tris = quad(24.5 - 32, 24.5 - 32, 40.5 - 32, 40.5 - 32, -2.0);
  for (Tri& t : tris)
    for (int v = 0; v < 3; ++v) {
      t.uv[v][0] = (t.p[v][0] + 32 - 24.5) / 16;
      t.uv[v][1] = (t.p[v][1] + 32 - 24.5) / 16;
    }
  auto mats = default_materials();
  mats[0].normal_map = 0;
  auto encode = [](const double n[3], float* px) {
    for (int k = 0; k < 3; ++k) px[k] = static_cast<float>(n[k] * 0.5 + 0.5);
    px[3] = 1.0f;
  };

  // Flat map: normals unchanged.
  Image flat_map(4, 4);
  const double up[3] = {0, 0, 1};
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) encode(up, flat_map.px(x, y));
  {
    const auto g = run(tris, p, w, h, mats, {flat_map});
    EXPECT_EQ(covered(g.position), 256);
    for (int y = 24; y <= 39; ++y)
      for (int x = 24; x <= 39; ++x) {
        const float* n = g.normal.px(x, y);
        ASSERT_NEAR(n[0], 0.0f, 1e-6);
        ASSERT_NEAR(n[1], 0.0f, 1e-6);
        ASSERT_NEAR(n[2], 1.0f, 1e-6);
      }
  }

  // 2 x 2 map: bottom-left tilted 30 degrees toward +T, bottom-right 20
  // degrees toward +B, top-left 40 degrees toward -T, top-right flat.
  const double t30 = 30 * kPi / 180, t20 = 20 * kPi / 180, t40 = 40 * kPi / 180;
  const double bl[3] = {std::sin(t30), 0, std::cos(t30)}, br[3] = {0, std::sin(t20), std::cos(t20)};
  const double tl[3] = {-std::sin(t40), 0, std::cos(t40)};
  Image map(2, 2);
  encode(bl, map.px(0, 0)), encode(br, map.px(1, 0)), encode(tl, map.px(0, 1)), encode(up, map.px(1, 1));
  for (double sign : {1.0, -1.0}) {
    // Tangent along view -x (so T = (-1, 0, 0)), bitangent sign `sign`:
    // B = sign * cross(N, T) = sign * (0, -1, 0).
    for (Tri& t : tris)
      for (int v = 0; v < 3; ++v) t.t[v][0] = -1, t.t[v][1] = 0, t.t[v][2] = 0, t.t[v][3] = sign;
    const auto g = run(tris, p, w, h, mats, {map});
    auto expect_normal = [&](int x, int y, double ex, double ey, double ez) {
      const float* n = g.normal.px(x, y);
      EXPECT_NEAR(n[0], ex, 1e-5) << x << "," << y;
      EXPECT_NEAR(n[1], ey, 1e-5) << x << "," << y;
      EXPECT_NEAR(n[2], ez, 1e-5) << x << "," << y;
    };
    expect_normal(28, 28, -std::sin(t30), 0, std::cos(t30));
    expect_normal(36, 28, 0, -sign * std::sin(t20), std::cos(t20));
    expect_normal(28, 36, std::sin(t40), 0, std::cos(t40));
    expect_normal(36, 36, 0, 0, 1);
    const float* n = g.normal.px(28, 28);
    EXPECT_NEAR(std::acos(std::min(1.0f, n[2])), t30, 1e-5);  // rotated by the expected angle
  }
}

// Many random triangles (some crossing the near plane) against a brute-force
// ray/triangle reference: the nearest hit of each pixel's ray.
TEST(Raster, RandomSoupMatchesBruteForceRayCast) {
  const int w = 64, h = 48, count = 150;
  const Mat4 p = perspective(1.0, double(w) / h, 0.2, 30.0);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Tri> tris;
  for (int i = 0; i < count; ++i) {
    const double cx = 4 * u(rng), cy = 3 * u(rng), cz = -6 + 5 * u(rng);
    double n[3] = {u(rng), u(rng), u(rng)};
    const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (double& v : n) v /= l;
    double q[3][3];
    for (auto& v : q) v[0] = cx + 2 * u(rng), v[1] = cy + 2 * u(rng), v[2] = cz + 2 * u(rng);
    tris.push_back(flat(q[0], q[1], q[2], n, i % 2));
  }
  const auto g = run(tris, p, w, h);
  const Mesh mesh = make_mesh(tris);  // the float corners the rasterizer saw
  int compared = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double d[3] = {((x + 0.5) / w * 2 - 1) / p(0, 0), ((y + 0.5) / h * 2 - 1) / p(1, 1), -1.0};
      double best = 1e300, second = 1e300, best_margin = 0;
      int best_id = -1;
      bool ambiguous = false;
      for (int i = 0; i < count; ++i) {
        const float* c = mesh.positions.data() + 9 * i;
        // Moller-Trumbore.
        double e1[3], e2[3], s[3];
        for (int k = 0; k < 3; ++k) e1[k] = c[3 + k] - c[k], e2[k] = c[6 + k] - c[k], s[k] = -c[k];
        const double pv[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
        const double det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
        if (std::fabs(det) < 1e-12) continue;
        const double b1 = (s[0] * pv[0] + s[1] * pv[1] + s[2] * pv[2]) / det;
        const double qv[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
        const double b2 = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) / det;
        const double t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) / det;
        const double margin = std::min({b1, b2, 1 - b1 - b2, t - 0.2, 30.0 - t});
        if (std::fabs(margin) < 1e-3) ambiguous = true;  // on an edge or a clip plane
        if (margin < 0) continue;
        if (t < best) second = best, best = t, best_id = i, best_margin = margin;
        else if (t < second) second = t;
      }
      (void)best_margin;
      if (ambiguous || (second - best) < 1e-6) continue;
      const float* q = g.position.px(x, y);
      ASSERT_EQ(q[3] == 1.0f, best_id >= 0) << x << "," << y;
      if (best_id < 0) continue;
      ++compared;
      for (int k = 0; k < 3; ++k) ASSERT_NEAR(q[k], d[k] * best, 1e-5 * best) << x << "," << y;
      EXPECT_EQ(g.specular.px(x, y)[0], best_id % 2 ? 1.0f : 0.25f);
    }
  EXPECT_GT(compared, w * h / 3);
}

TEST(Raster, ResultDoesNotDependOnTheThreadCount) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Tri> tris;
  for (int i = 0; i < 3000; ++i) {
    double q[3][3], n[3] = {0, 0, 1};
    const double cx = 3 * u(rng), cy = 2 * u(rng), cz = -5 + 2 * u(rng);
    for (auto& v : q) v[0] = cx + 0.5 * u(rng), v[1] = cy + 0.5 * u(rng), v[2] = cz + 0.5 * u(rng);
    tris.push_back(flat(q[0], q[1], q[2], n, i % 2));
  }
  const Mat4 p = perspective(1.0, 1.5, 0.1, 100);
  const auto one = run(tris, p, 150, 100, default_materials(), {}, 1);
  const auto four = run(tris, p, 150, 100, default_materials(), {}, 4);
  EXPECT_EQ(one.position.data, four.position.data);
  EXPECT_EQ(one.normal.data, four.normal.data);
  EXPECT_EQ(one.specular.data, four.specular.data);
}

// More triangles than the rasterizer sets up at once (65536): the layers
// still come out as the analytic scene has them, across the chunks. A wall
// at z = -10 and a back face at z = -12 behind its left half come first; then
// 70000 triangles behind the eye; then a slab (front face at z = -5, back
// face at z = -8, 4 x 4 wide). Under the square 90-degree camera a point
// (x, y, z) is seen at ndc (x / -z, y / -z).
TEST(Raster, MoreTrianglesThanOneChunkKeepBothLayers) {
  const int w = 64, h = 64;
  std::vector<Tri> tris = quad(-20, -20, 20, 20, -10.0, false, 0);
  const auto left_back = quad(-20, -20, 0, 20, -12.0, true, 0);
  tris.insert(tris.end(), left_back.begin(), left_back.end());
  const double a[3] = {0, 0, 1}, b[3] = {1, 0, 1}, c[3] = {0, 1, 2}, n[3] = {0, 0, 1};
  tris.insert(tris.end(), 70000, flat(a, b, c, n));
  for (const auto& part : {quad(-2, -2, 2, 2, -5.0, false, 1), quad(-2, -2, 2, 2, -8.0, true, 1)})
    tris.insert(tris.end(), part.begin(), part.end());
  const Mesh mesh = make_mesh(tris);
  auto mats = default_materials();
  mats[0].albedo[0] = 0.5f;
  mats[1].albedo[1] = 0.75f;
  const std::vector<Image> maps;
  RasterInputs in{mesh, mats, maps, square_perspective(), w, h};
  in.back_layer = true;
  in.back_albedo = true;
  const GBufferImages g = cpu::rasterize(in, 2);

  int checked = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double nx = (x + 0.5) / w * 2 - 1, ny = (y + 0.5) / h * 2 - 1;
      const double r = std::max(std::fabs(nx), std::fabs(ny));
      // Away from every edge of the scene (0.4 and 0.25: the slab's faces).
      if (std::fabs(r - 0.4) < 0.05 || std::fabs(r - 0.25) < 0.05 || std::fabs(nx) < 0.05) continue;
      const double front = r < 0.4 ? -5.0 : -10.0;
      const double back = r < 0.25 ? -8.0 : (nx < 0 ? -12.0 : 0.0);
      const float* p = g.position.px(x, y);
      ASSERT_NEAR(p[0], nx * -front, 1e-5 * -front) << x << "," << y;
      ASSERT_NEAR(p[1], ny * -front, 1e-5 * -front) << x << "," << y;
      ASSERT_NEAR(p[2], front, 1e-5 * -front) << x << "," << y;
      EXPECT_EQ(g.specular.px(x, y)[0], r < 0.4 ? 1.0f : 0.25f) << x << "," << y;
      EXPECT_EQ(g.normal.px(x, y)[2], 1.0f) << x << "," << y;
      const float* q = g.back_position.px(x, y);
      ASSERT_EQ(q[3], back != 0.0 ? 1.0f : 0.0f) << x << "," << y;
      if (back != 0.0) ASSERT_NEAR(q[2], back, 1e-5 * -back) << x << "," << y;
      // The slab's back face is material 1, the wall's back face material 0.
      const float* al = g.back_albedo.px(x, y);
      ASSERT_EQ(al[0], back == -12.0 ? 0.5f : 0.0f) << x << "," << y;
      ASSERT_EQ(al[1], back == -8.0 ? 0.75f : 0.0f) << x << "," << y;
      ASSERT_EQ(al[3], q[3]) << x << "," << y;
      ++checked;
    }
  EXPECT_GT(checked, w * h / 2);
}

// back_albedo is the albedo of the back-layer triangle's material: a small
// box (material 0) in front of a larger one (material 1) in front of an open
// wall (material 1, front-facing, so no back layer where it is the front).
// Under the square 90-degree camera a point (x, y, z) is seen at ndc
// (x / -z, y / -z): the small box covers max(|nx|, |ny|) < 0.5 / 3, the large
// one < 2 / 6; the small box's far face (z = -4) shows within 0.5 / 4, the
// large one's (z = -9) within 2 / 9 where the small box does not hide it.
TEST(Raster, BackAlbedoIsTheMaterialOfTheBackLayersTriangle) {
  const int w = 64, h = 64;
  const double big_lo[3] = {-2, -2, -9}, big_hi[3] = {2, 2, -6};
  const double small_lo[3] = {-0.5, -0.5, -4}, small_hi[3] = {0.5, 0.5, -3};
  // The far box first: which layer wins is the depth's doing, not the order's.
  std::vector<Tri> tris = box(big_lo, big_hi, 1);
  for (const auto& part : {box(small_lo, small_hi, 0), quad(-40, -40, 40, 40, -20.0, false, 1)})
    tris.insert(tris.end(), part.begin(), part.end());
  const Mesh mesh = make_mesh(tris);
  auto mats = default_materials();
  const float albedo[2][3] = {{0.8f, 0.1f, 0.2f}, {0.1f, 0.6f, 0.3f}};
  for (int m = 0; m < 2; ++m)
    for (int c = 0; c < 3; ++c) mats[m].albedo[c] = albedo[m][c];
  const std::vector<Image> maps;
  RasterInputs in{mesh, mats, maps, square_perspective(), w, h};
  in.back_layer = true;
  const GBufferImages plain = cpu::rasterize(in, 2);
  EXPECT_TRUE(plain.back_albedo.empty());
  in.back_albedo = true;
  for (int threads : {1, 2}) {
    const GBufferImages g = cpu::rasterize(in, threads);
    ASSERT_EQ(g.back_albedo.width, w);
    ASSERT_EQ(g.back_albedo.height, h);
    EXPECT_EQ(g.back_position.data, plain.back_position.data);  // the albedo changes no other layer
    int per_material[2] = {0, 0}, bare_front = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double nx = (x + 0.5) / w * 2 - 1, ny = (y + 0.5) / h * 2 - 1;
        const double r = std::max(std::fabs(nx), std::fabs(ny));
        const int expect = r < 0.5 / 3 ? 0 : (r < 2.0 / 6 ? 1 : -1);
        const float* bp = g.back_position.px(x, y);
        const float* a = g.back_albedo.px(x, y);
        if (expect < 0) {
          ASSERT_EQ(bp[3], 0.0f) << x << "," << y;
          ASSERT_EQ(g.position.px(x, y)[3], 1.0f) << x << "," << y;  // the wall
          ++bare_front;
        } else {
          ASSERT_EQ(bp[3], 1.0f) << x << "," << y;
          if (r < 0.5 / 4) ASSERT_NEAR(bp[2], -4.0f, 4e-5f) << x << "," << y;
          if (r > 0.5 / 3 && r < 2.0 / 9) ASSERT_NEAR(bp[2], -9.0f, 9e-5f) << x << "," << y;
          ++per_material[expect];
        }
        for (int c = 0; c < 3; ++c)
          ASSERT_EQ(a[c], expect < 0 ? 0.0f : albedo[expect][c]) << x << "," << y << " channel " << c;
        ASSERT_EQ(a[3], bp[3]) << x << "," << y;
      }
    EXPECT_GT(per_material[0], 50);
    EXPECT_GT(per_material[1], 200);
    EXPECT_GT(bare_front, 1000);
  }
}

TEST(Raster, BackAlbedoBadInputNamesTheArgument) {
  const Mesh mesh = make_mesh(quad(-0.5, -0.5, 0.5, 0.5, -2.0));
  const std::vector<Image> maps;
  auto error_of = [&](const std::vector<Material>& mats, bool back_layer) -> std::string {
    RasterInputs in{mesh, mats, maps, square_perspective(), 8, 8};
    in.back_layer = back_layer;
    in.back_albedo = true;
    try {
      cpu::rasterize(in, 1);
    } catch (const InvalidArgument& e) {
      return e.argument() + " | " + e.what();
    }
    return "no error";
  };
  auto mats = default_materials();
  EXPECT_EQ(error_of(mats, false).rfind("back_albedo | ", 0), 0u) << error_of(mats, false);
  mats[1].albedo[2] = -0.25f;
  const std::string negative = error_of(mats, true);
  EXPECT_EQ(negative.rfind("material_albedo | ", 0), 0u) << negative;
  EXPECT_NE(negative.find("row 1"), std::string::npos) << negative;
  mats[1].albedo[2] = std::numeric_limits<float>::infinity();
  EXPECT_EQ(error_of(mats, true).rfind("material_albedo | ", 0), 0u) << error_of(mats, true);
  mats[1].albedo[2] = std::nanf("");
  EXPECT_EQ(error_of(mats, true).rfind("material_albedo | ", 0), 0u) << error_of(mats, true);
  mats[1].albedo[2] = 0.0f;
  EXPECT_EQ(error_of(mats, true), "no error");
}

TEST(Raster, NonFiniteCornersSkipTheTriangleOnly) {
  auto tris = quad(-0.5, -0.5, 0.5, 0.5, -2.0);
  tris[0].p[1][0] = std::nan("");
  tris[1].n[0][0] = std::numeric_limits<double>::infinity();  // bad normal: face normal instead
  const auto g = run(tris, square_perspective(), 64, 64);
  // Only the upper-left triangle (a, c, d) remains: the centres strictly
  // above the diagonal. Those on it belong to the skipped triangle, whose
  // left edge the diagonal is.
  EXPECT_EQ(covered(g.position), 16 * 15 / 2);
  for (float v : g.normal.data) ASSERT_TRUE(std::isfinite(v));
  EXPECT_NEAR(g.normal.px(26, 37)[2], 1.0f, 1e-6);
}

namespace {
void expect_error(const char* argument, const std::function<void(Mesh&, std::vector<Material>&,
                                                                   std::vector<Image>&, int&, int&)>& edit) {
  Mesh mesh = make_mesh(quad(-0.5, -0.5, 0.5, 0.5, -2.0), true);
  auto mats = default_materials();
  std::vector<Image> maps{Image(2, 2, 0.5f)};
  int w = 16, h = 16;
  edit(mesh, mats, maps, w, h);
  try {
    cpu::rasterize(RasterInputs{mesh, mats, maps, square_perspective(), w, h}, 1);
    ADD_FAILURE() << "no error for " << argument;
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(e.argument(), argument) << e.what();
  }
}
}  // namespace

TEST(Raster, BadInputNamesTheArgument) {
  using M = Mesh;
  using V = std::vector<Material>;
  using I = std::vector<Image>;
  expect_error("positions", [](M& m, V&, I&, int&, int&) { m.positions.pop_back(); });
  expect_error("normals", [](M& m, V&, I&, int&, int&) { m.normals.push_back(0); });
  expect_error("material_index", [](M& m, V&, I&, int&, int&) { m.material[1] = 2; });
  expect_error("material_index", [](M& m, V&, I&, int&, int&) { m.material[0] = -1; });
  expect_error("materials", [](M&, V& v, I&, int&, int&) { v.clear(); });
  expect_error("materials", [](M&, V& v, I&, int&, int&) { v[1].shininess = std::nanf(""); });
  expect_error("material_normal_map", [](M&, V& v, I&, int&, int&) { v[0].normal_map = 1; });
  expect_error("material_normal_map", [](M&, V& v, I&, int&, int&) { v[0].normal_map = -2; });
  expect_error("uvs", [](M& m, V& v, I&, int&, int&) { v[0].normal_map = 0, m.uvs.clear(); });
  expect_error("uvs", [](M& m, V&, I&, int&, int&) { m.uvs.resize(5); });
  expect_error("tangents", [](M& m, V& v, I&, int&, int&) { v[0].normal_map = 0, m.tangents.clear(); });
  expect_error("normal_maps[0]", [](M&, V&, I& i, int&, int&) { i[0] = Image(); });
  expect_error("width", [](M&, V&, I&, int& w, int&) { w = 0; });
  expect_error("height", [](M&, V&, I&, int&, int& h) { h = 40000; });
  // uvs / tangents may be absent when no material uses a normal map.
  Mesh mesh = make_mesh(quad(-0.5, -0.5, 0.5, 0.5, -2.0), false);
  const auto mats = default_materials();
  const std::vector<Image> none;
  EXPECT_NO_THROW(cpu::rasterize(RasterInputs{mesh, mats, none, square_perspective(), 8, 8}, 1));
  Mat4 singular;
  try {
    cpu::rasterize(RasterInputs{mesh, mats, none, singular, 8, 8}, 1);
    ADD_FAILURE() << "no error for a singular projection";
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(e.argument(), "projection");
  }
}

TEST(Raster, CpuBackendRasterizes) {
  const Mesh mesh = make_mesh(quad(-0.5, -0.5, 0.5, 0.5, -2.0));
  const auto mats = default_materials();
  const std::vector<Image> none;
  const auto g = make_cpu_backend(2)->rasterize(RasterInputs{mesh, mats, none, square_perspective(), 64, 64});
  EXPECT_EQ(covered(g.position), 256);
}
