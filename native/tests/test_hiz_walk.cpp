// The hiz march's walks (native/marches/hiz/hiz_walk.h) give the same answers bit
// for bit: the AVX2 walk, eight rays at once, against the scalar one, on the
// analytic scene with every option that changes which path a ray takes.
#include <gtest/gtest.h>

#include <cstring>

#include "analytic_scene.h"
#include "glint/marches.h"
#include "glint/stages.h"
#include "hiz/hiz.h"

using namespace glint;

namespace {

// The number of pixels whose four floats differ in any bit.
int differing_pixels(const Image& a, const Image& b) {
  int n = 0;
  for (size_t p = 0; p < a.pixel_count(); ++p)
    n += std::memcmp(a.data.data() + 4 * p, b.data.data() + 4 * p, 4 * sizeof(float)) != 0;
  return n;
}

TEST(HizWalk, Avx2WalkMatchesTheScalarWalkBitForBit) {
  if (!cpu::hiz_walk_available(cpu::WalkIsa::Avx2)) GTEST_SKIP() << "this CPU has no AVX2";
  // Odd sizes: the last cell of a row or column covers what is left over.
  for (const auto& size : {std::pair<int, int>{161, 97}, {320, 240}}) {
    for (const bool ortho : {false, true}) {
      const int w = size.first, h = size.second;
      const Mat4 proj = ortho ? orthographic(4.0 * w / h, 4.0, 0.1, 100.0)
                              : perspective(1.0, static_cast<double>(w) / h, 0.1, 100.0);
      // A mirror floor and a near wall, so that most floor rays meet the
      // wall or the sphere on screen, and the wall's own rays come back. The
      // orthographic camera would see a level floor edge-on: it is tilted.
      test::Scene scene;
      if (ortho)
        scene.planes.push_back({{0, 0.8, 0.6}, -3.8, {0.5f, 0.5f, 0.5f}, 1.0f, 1.0f});
      else
        scene.planes.push_back({{0, 1, 0}, -1.0, {0.5f, 0.5f, 0.5f}, 1.0f, 1.0f});
      scene.planes.push_back({{0, 0, 1}, -6.0, {0.1f, 0.2f, 0.9f}, 1.0f, 1.0f});
      scene.spheres.push_back({{0.3, -0.2, -4.0}, 0.8, {0.9f, 0.1f, 0.1f}, 1.0f, 1.0f});
      const test::GBuffer g = test::render(scene, proj, w, h);
      for (const int steps : {0, 2, 10}) {
        for (const float resolution : {0.3f, 1.0f}) {  // with and without reusing rays
          for (const Blocked blocked : {Blocked::Miss, Blocked::Occluder}) {
            TraceOptions opt;
            opt.march = March::Hiz;
            opt.steps = steps;
            opt.resolution = resolution;
            opt.thickness = 0.3f;
            opt.blocked = blocked;
            // No specular buffer: every seen pixel sends its ray.
            TraceInputs in{g.position, g.normal, nullptr, g.projection};
            const Image scalar = cpu::trace_hiz(in, opt, 2, cpu::WalkIsa::Scalar);
            const Image avx2 = cpu::trace_hiz(in, opt, 2, cpu::WalkIsa::Avx2);
            EXPECT_EQ(differing_pixels(scalar, avx2), 0)
                << w << "x" << h << (ortho ? " ortho" : " persp") << " steps " << steps << " resolution "
                << resolution << " blocked " << static_cast<int>(blocked);
            // The walk does find hits here, so that equal answers mean something.
            if (steps == 10) {
              int hits = 0;
              for (size_t p = 0; p < scalar.pixel_count(); ++p) hits += scalar.data[4 * p + 2] > 0.0f;
              EXPECT_GT(hits, w * h / 8) << w << "x" << h << (ortho ? " ortho" : " persp");
            }
          }
        }
      }
    }
  }
}

}  // namespace
