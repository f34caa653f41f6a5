// The seed march on exact analytic G-buffers against the mirror hit computed
// by hand, plus the extremes that must stay finite and bounded.
#include <gtest/gtest.h>

#include <cmath>

#include "analytic_scene.h"
#include "glint/marches.h"
#include "glint/stages.h"

using namespace glint;

namespace {

// A floor plane y = -1 and a wall z = -zw. A floor pixel at p reflects along
// r = reflect(normalize(p), up); where r meets the wall is the exact hit.
struct FloorWall {
  test::GBuffer g;
  double wall_z;
};

FloorWall floor_wall(int w, int h, double wall_z) {
  test::Scene s;
  s.planes.push_back({{0, 1, 0}, -1.0, {0.5f, 0.5f, 0.5f}, 1.0f, 1.0f});
  s.planes.push_back({{0, 0, 1}, -wall_z, {0.2f, 0.3f, 0.9f}, 0.0f, 0.0f});
  return {test::render(s, perspective(1.0, double(w) / h, 0.1, 100.0), w, h), wall_z};
}

}  // namespace

TEST(SeedMarch, FloorReflectsWallAtTheMirrorPoint) {
  const int w = 96, h = 64;
  FloorWall fw = floor_wall(w, h, 8.0);
  auto cpu = make_cpu_backend(2);
  TraceOptions opt;
  opt.resolution = 1.0f;
  opt.steps = 16;
  opt.thickness = 0.5f;
  Image uv = cpu->trace({fw.g.position, fw.g.normal, nullptr, fw.g.projection}, opt);
  int checked = 0, close = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const float* p = fw.g.position.px(x, y);
      if (p[3] == 0.0f || fw.g.normal.px(x, y)[1] < 0.5f) continue;  // floor pixels only
      const float* o = uv.px(x, y);
      // Exact: reflect the view ray about +y, intersect z = -8.
      double d[3] = {p[0], p[1], p[2]};
      const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      for (double& v : d) v /= len;
      d[1] = -d[1];
      const double t = (-fw.wall_z - p[2]) / d[2];
      const double hit[3] = {p[0] + d[0] * t, p[1] + d[1] * t, -fw.wall_z};
      const double dist = t;
      if (dist > opt.max_distance * 0.9) continue;
      const double cw = -hit[2];
      const Mat4& P = fw.g.projection;
      const double u = (P(0, 0) * hit[0] / cw) * 0.5 + 0.5, v = (P(1, 1) * hit[1] / cw) * 0.5 + 0.5;
      if (u < 0.02 || u > 0.98 || v < 0.02 || v > 0.98) continue;
      ++checked;
      if (o[2] > 0.0f && std::fabs(o[0] - u) * w < 2.0 && std::fabs(o[1] - v) * h < 2.0) ++close;
    }
  }
  ASSERT_GT(checked, 200);
  EXPECT_GT(double(close) / checked, 0.95) << close << " of " << checked;
}

TEST(SeedMarch, NothingToFindReportsNoVisibility) {
  // A lone floor with no wall: every reflected ray leaves into empty space.
  test::Scene s;
  s.planes.push_back({{0, 1, 0}, -1.0, {0.5f, 0.5f, 0.5f}, 1.0f, 1.0f});
  auto g = test::render(s, perspective(1.0, 1.5, 0.1, 100.0), 60, 40);
  auto cpu = make_cpu_backend(1);
  Image uv = cpu->trace({g.position, g.normal, nullptr, g.projection}, TraceOptions{});
  for (size_t i = 0; i < uv.pixel_count(); ++i) EXPECT_EQ(uv.data[i * 4 + 2], 0.0f);
}

TEST(SeedMarch, ExtremesStayFiniteAndInRange) {
  const int w = 40, h = 30;
  for (double near : {1e-4, 0.1}) {
    const double far = near < 1e-3 ? 1e7 : 100.0;
    test::Scene s = test::mirror_floor_scene();
    auto g = test::render(s, perspective(1.2, double(w) / h, near, far), w, h);
    // Rays straight back at the camera: normals facing the eye.
    for (int x = 0; x < w; ++x) {
      float* p = g.position.px(x, 0);
      float* n = g.normal.px(x, 0);
      const float l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      for (int k = 0; k < 3; ++k) n[k] = -p[k] / l;
    }
    g.normal.px(3, 3)[0] = NAN;
    g.normal.px(4, 3)[0] = g.normal.px(4, 3)[1] = g.normal.px(4, 3)[2] = 0.0f;
    g.position.px(5, 3)[2] = INFINITY;
    auto cpu = make_cpu_backend(2);
    for (const MarchInfo& info : march_table()) {
      if (info.needs_mesh) continue;
      const March m = info.id;
      for (float md : {0.0f, 1e6f}) {
        for (float th : {0.0f, 1e6f}) {
          for (float res : {0.0f, 1.0f}) {
            TraceOptions o;
            o.march = m;
            o.max_distance = md;
            o.thickness = th;
            o.resolution = res;
            o.steps = 1000;
            Image uv = cpu->trace({g.position, g.normal, nullptr, g.projection}, o);
            for (float v : uv.data) ASSERT_TRUE(std::isfinite(v));
            for (size_t i = 0; i < uv.pixel_count(); ++i) {
              ASSERT_GE(uv.data[i * 4 + 2], 0.0f);
              ASSERT_LE(uv.data[i * 4 + 2], 1.0f);
            }
          }
        }
      }
    }
  }
}

TEST(SeedMarch, RayWhoseEndsProjectAFloatRangeApartEnds) {
  // A point 1e-29 in front of a 1e-30 near plane, 1e8 to the right, whose
  // normal turns the view ray back to the left: the start projects to
  // x ~ +3e38 pixels and the end to x ~ -1e38, so delta_x overflows to -inf
  // and the increment is -inf / inf = NaN. No sample is on the image, and
  // the last one is NaN, so the seed reports nothing (FIX 4) -- promptly.
  const int w = 64, h = 64;
  const double near = 1e-30, far = 10.0;
  Mat4 P;
  P(0, 0) = 1.0;
  P(1, 1) = 1.0;
  P(2, 2) = -(far + near) / (far - near);
  P(2, 3) = -2.0 * far * near / (far - near);
  P(3, 2) = -1.0;
  Image pos(w, h), nrm(w, h);
  float* p = pos.px(32, 32);
  p[0] = 1e8f;
  p[2] = -1e-29f;
  p[3] = 1.0f;
  nrm.px(32, 32)[0] = 1.0f;
  TraceOptions o;
  o.max_distance = 2e8f;
  auto cpu = make_cpu_backend(1);
  Image uv = cpu->trace({pos, nrm, nullptr, P}, o);
  for (float v : uv.data) ASSERT_EQ(v, 0.0f);
}
