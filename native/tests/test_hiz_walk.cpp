// The hiz march's walks (native/marches/hiz/hiz_walk.h) give the same answers bit
// for bit: the AVX2 walk, sixteen rays at once, against the scalar one, on the
// analytic scene with every option that changes which path a ray takes; the
// pyramid built eight texels at a time against the scalar one; the reuse
// test's G-buffer half, the pixels' own rays and the outline samples' rays,
// eight at a time against the scalar ones; the outline search's report bytes
// sixteen at a time against report_of().
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "analytic_scene.h"
#include "cpu/march.h"
#include "cpu/outline.h"
#include "glint/marches.h"
#include "glint/stages.h"
#include "hiz/hiz.h"
#include "hiz/hiz_base.h"

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

// The plane normals and the base level are the scalar rule's bit for bit:
// widths around the AVX2 rows' edges (12 is the least they take; the rest of
// a row goes to the scalar rule), rows near the top and bottom (neighbours two
// rows away off the image), outlines against the sky (unseen neighbours on
// either side), and shading normals the rule must pass through unchanged.
TEST(HizWalk, Avx2PyramidMatchesTheScalarOneBitForBit) {
  if (!cpu::hiz_walk_available(cpu::WalkIsa::Avx2)) GTEST_SKIP() << "this CPU has no AVX2";
  for (const auto& size : {std::pair<int, int>{12, 1}, {13, 2}, {19, 3}, {27, 5}, {41, 9}, {161, 97}}) {
    const int w = size.first, h = size.second;
    const Mat4 proj = perspective(1.0, static_cast<double>(w) / h, 0.1, 100.0);
    test::Scene scene;
    scene.planes.push_back({{0, 1, 0}, -1.0, {0.5f, 0.5f, 0.5f}, 1.0f, 1.0f});
    scene.spheres.push_back({{0.3, -0.2, -4.0}, 0.8, {0.9f, 0.1f, 0.1f}, 1.0f, 1.0f});
    scene.spheres.push_back({{-0.6, 0.1, -2.5}, 0.25, {0.1f, 0.9f, 0.1f}, 1.0f, 1.0f});
    test::GBuffer g = test::render(scene, proj, w, h);
    // A few texels whose shading normal is not a direction: NaN, zero, infinite.
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    for (int k = 0; k < w * h; k += 7) {
      float* n = g.normal.data.data() + 4 * static_cast<size_t>(k);
      const int kind = (k / 7) % 5;
      if (kind == 1) n[0] = nan;
      if (kind == 2) n[0] = n[1] = n[2] = 0.0f;
      if (kind == 3) n[2] = inf;
      // And positions the seen flags must turn away: NaN, infinite, w <= 0.
      float* p = g.position.data.data() + 4 * static_cast<size_t>(k);
      if (kind == 4) p[(k / 35) % 4] = (k / 140) % 2 ? nan : inf;
      if (kind == 0 && (k / 35) % 3 == 1) p[3] = -1.0f;
    }
    const cpu::HizCamera cam = cpu::hiz_camera(g.projection);
    cpu::HizPlanes planes_scalar, planes_avx2;
    const cpu::HizPyramid scalar = cpu::build_hiz_pyramid(g.position, g.normal, nullptr, cam, 0.3f, 2,
                                                          planes_scalar, cpu::WalkIsa::Scalar);
    const cpu::HizPyramid avx2 =
        cpu::build_hiz_pyramid(g.position, g.normal, nullptr, cam, 0.3f, 2, planes_avx2, cpu::WalkIsa::Avx2);
    ASSERT_EQ(planes_scalar.xyz.size(), planes_avx2.xyz.size());
    int planes_differ = 0, planes_rebuilt = 0;
    for (size_t t = 0; t < g.position.pixel_count(); ++t) {
      const float* a = planes_scalar.xyz.data() + 3 * t;
      planes_differ += std::memcmp(a, planes_avx2.xyz.data() + 3 * t, 3 * sizeof(float)) != 0;
      const float* n = g.normal.data.data() + 4 * t;
      planes_rebuilt += std::memcmp(a, n, 3 * sizeof(float)) != 0;
    }
    EXPECT_EQ(planes_differ, 0) << w << "x" << h;
    // The rule does rebuild normals (on the largest image: the spheres'
    // geometric normals differ from their shading normals in the last bits, a
    // level floor's do not), so that equal planes mean something.
    if (w * h > 1000) EXPECT_GT(planes_rebuilt, w * h / 20) << w << "x" << h;
    ASSERT_EQ(scalar.range.size(), avx2.range.size());
    EXPECT_EQ(std::memcmp(scalar.range.data(), avx2.range.data(), scalar.range.size() * sizeof(float)), 0)
        << w << "x" << h;
  }
}

// The reuse test's surface half (hiz_reuse_surface_row()) gives the scalar
// bytes on every row: widths around the AVX2 rows' edges (10 is the least
// they take), both row parities and the last row, with and without a
// specular buffer, and texels that must fail it: unseen, NaN positions,
// NaN, zero and infinite normals, specular 0, negative or NaN.
TEST(HizWalk, Avx2ReuseTestMatchesTheScalarOneBitForBit) {
  if (!cpu::hiz_walk_available(cpu::WalkIsa::Avx2)) GTEST_SKIP() << "this CPU has no AVX2";
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (const auto& size : {std::pair<int, int>{10, 3}, {11, 4}, {18, 5}, {27, 8}, {161, 97}}) {
    const int w = size.first, h = size.second;
    const Mat4 proj = perspective(1.0, static_cast<double>(w) / h, 0.1, 100.0);
    test::Scene scene;
    scene.planes.push_back({{0, 1, 0}, -1.0, {0.5f, 0.5f, 0.5f}, 1.0f, 1.0f});
    scene.spheres.push_back({{0.3, -0.2, -4.0}, 0.8, {0.9f, 0.1f, 0.1f}, 1.0f, 1.0f});
    test::GBuffer g = test::render(scene, proj, w, h);
    Image specular(w, h);
    for (size_t t = 0; t < g.position.pixel_count(); ++t) {
      float* p = g.position.data.data() + 4 * t;
      float* n = g.normal.data.data() + 4 * t;
      float* s = specular.data.data() + 4 * t;
      s[0] = s[1] = s[2] = 0.5f;
      switch (t % 41) {
        case 3: p[3] = 0.0f; break;
        case 5: p[1] = nan; break;
        case 8: n[0] = nan; break;
        case 11: n[0] = n[1] = n[2] = 0.0f; break;
        case 14: n[2] = inf; break;
        case 17: s[0] = s[1] = s[2] = 0.0f; break;
        case 19: s[1] = -2.0f; break;
        case 21: s[2] = nan; break;
        default: break;
      }
    }
    for (const bool with_specular : {false, true}) {
      TraceInputs in{g.position, g.normal, with_specular ? &specular : nullptr, g.projection};
      std::vector<unsigned char> scalar(w), avx2(w);
      int differ = 0, passed = 0, failed = 0;
      for (int y = 0; y < h; ++y) {
        cpu::hiz_reuse_surface_row(in, y, cpu::WalkIsa::Scalar, scalar.data());
        cpu::hiz_reuse_surface_row(in, y, cpu::WalkIsa::Avx2, avx2.data());
        for (int x = 0; x < w; ++x) {
          differ += scalar[x] != avx2[x];
          const bool second_pass = (y & 1) || (x & 1);
          passed += second_pass && scalar[x];
          failed += second_pass && !scalar[x];
        }
      }
      EXPECT_EQ(differ, 0) << w << "x" << h << (with_specular ? " with specular" : "");
      // Both answers occur, so that equal bytes mean something.
      if (w * h > 1000) {
        EXPECT_GT(passed, w * h / 20) << w << "x" << h;
        EXPECT_GT(failed, w * h / 8) << w << "x" << h;
      }
    }
  }
}

// The pixels' own rays (hiz_pixel_rays()) are the scalar ones bit for bit:
// both cameras and the eye of a general projective one, rows whose length is
// not a multiple of 8, a sphere just past the near plane whose rays come back
// toward the camera and are cut short there, lengths from 0.05 to 1e7, and
// texels that have no ray: unseen, NaN or infinite positions, a position at
// the eye, NaN, zero and infinite normals.
TEST(HizWalk, Avx2PixelRaysMatchTheScalarOnesBitForBit) {
  if (!cpu::hiz_walk_available(cpu::WalkIsa::Avx2)) GTEST_SKIP() << "this CPU has no AVX2";
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (const auto& size : {std::pair<int, int>{13, 7}, {161, 97}}) {
    for (const bool ortho : {false, true}) {
      const int w = size.first, h = size.second;
      const Mat4 proj = ortho ? orthographic(4.0 * w / h, 4.0, 0.1, 100.0)
                              : perspective(1.0, static_cast<double>(w) / h, 0.1, 100.0);
      test::Scene scene;
      scene.planes.push_back({{0, 0.8, 0.6}, -3.8, {0.5f, 0.5f, 0.5f}, 1.0f, 1.0f});
      scene.spheres.push_back({{0.1, 0.0, -0.45}, 0.3, {0.9f, 0.1f, 0.1f}, 1.0f, 1.0f});
      test::GBuffer g = test::render(scene, proj, w, h);
      for (size_t t = 0; t < g.position.pixel_count(); ++t) {
        float* p = g.position.data.data() + 4 * t;
        float* n = g.normal.data.data() + 4 * t;
        switch (t % 37) {
          case 2: p[3] = 0.0f; break;
          case 4: p[0] = nan; break;
          case 6: p[2] = -inf; break;
          case 9: p[0] = p[1] = p[2] = 0.0f; break;
          case 12: n[1] = nan; break;
          case 15: n[0] = n[1] = n[2] = 0.0f; break;
          case 18: n[2] = inf; break;
          case 21: n[0] = -n[0], n[1] = -n[1], n[2] = -n[2]; break;
          default: break;
        }
      }
      for (const float max_distance : {0.05f, 100.0f, 1e7f}) {
        for (const bool point_eye : {false, true}) {
          TraceOptions opt;
          opt.march = March::Hiz;
          opt.max_distance = max_distance;
          cpu::MarchSetup s = cpu::make_setup(g.position, g.normal, g.projection, opt, nullptr);
          if (point_eye) {
            s.eye_kind = EyeKind::Point;
            s.eye[0] = 0.1f, s.eye[1] = -0.2f, s.eye[2] = 0.3f;
          }
          std::vector<int> xs(w);
          for (int x = 0; x < w; ++x) xs[x] = x;
          std::vector<cpu::RayFields> scalar(w), avx2(w);
          std::vector<unsigned char> made_scalar(w), made_avx2(w);
          int differ = 0, made = 0;
          for (int y = 0; y < h; ++y) {
            cpu::hiz_pixel_rays(s, y, xs.data(), w, cpu::WalkIsa::Scalar, scalar.data(), made_scalar.data());
            cpu::hiz_pixel_rays(s, y, xs.data(), w, cpu::WalkIsa::Avx2, avx2.data(), made_avx2.data());
            for (int x = 0; x < w; ++x) {
              made += made_scalar[x];
              differ += made_scalar[x] != made_avx2[x] ||
                        (made_scalar[x] && std::memcmp(&scalar[x], &avx2[x], sizeof(cpu::RayFields)) != 0);
            }
          }
          const std::string at = std::to_string(w) + "x" + std::to_string(h) + (ortho ? " ortho" : "") +
                                 (point_eye ? " point eye" : "") + " length " + std::to_string(max_distance);
          EXPECT_EQ(differ, 0) << at;
          // Both answers occur, so that equal rays mean something.
          EXPECT_GT(made, w * h / 2) << at;
          EXPECT_LT(made, w * h) << at;

          // The outline samples' rays (hiz_sample_rays()): every pixel from
          // the four antialiasing offsets and two near its corners, on the
          // plane normals of the pyramid, some of them unusable.
          const cpu::HizCamera cam = cpu::hiz_camera(g.projection);
          cpu::HizPlanes planes;
          cpu::build_hiz_pyramid(g.position, g.normal, nullptr, cam, 0.3f, 1, planes, cpu::WalkIsa::Scalar);
          for (size_t t = 0; t < g.position.pixel_count(); t += 29) {
            float* n = planes.xyz.data() + 3 * t;
            if (t % 3 == 0) n[1] = nan;
            if (t % 3 == 1) n[0] = n[1] = n[2] = 0.0f;
          }
          const float corners[6][2] = {{-0.125f, -0.375f}, {0.375f, -0.125f}, {0.125f, 0.375f},
                                       {-0.375f, 0.125f}, {0.3f, -0.49f},    {-0.5f, 0.1f}};
          std::vector<int> sxs;
          std::vector<float> offsets;
          for (int x = 0; x < w; ++x)
            for (const auto& c : corners) sxs.push_back(x), offsets.push_back(c[0]), offsets.push_back(c[1]);
          const int n = static_cast<int>(sxs.size());
          std::vector<cpu::RayFields> sample_scalar(n), sample_avx2(n);
          std::vector<unsigned char> sample_made_scalar(n), sample_made_avx2(n);
          int sample_differ = 0, sample_made = 0;
          for (int y = 0; y < h; ++y) {
            cpu::hiz_sample_rays(s, planes, cam, y, sxs.data(), offsets.data(), n, cpu::WalkIsa::Scalar,
                                 sample_scalar.data(), sample_made_scalar.data());
            cpu::hiz_sample_rays(s, planes, cam, y, sxs.data(), offsets.data(), n, cpu::WalkIsa::Avx2,
                                 sample_avx2.data(), sample_made_avx2.data());
            for (int k = 0; k < n; ++k) {
              sample_made += sample_made_scalar[k];
              sample_differ += sample_made_scalar[k] != sample_made_avx2[k] ||
                               (sample_made_scalar[k] &&
                                std::memcmp(&sample_scalar[k], &sample_avx2[k], sizeof(cpu::RayFields)) != 0);
            }
          }
          EXPECT_EQ(sample_differ, 0) << at << " (samples)";
          EXPECT_GT(sample_made, n * h / 2) << at << " (samples)";
          EXPECT_LT(sample_made, n * h) << at << " (samples)";
        }
      }
    }
  }
}

// The outline test's report bytes (cpu/outline.h), sixteen pixels at a time
// on x86-64, are report_of() pixel for pixel: widths around the sixteens,
// and the values where a compare could go the other way (-0, NaN in either
// channel, infinities, the smallest denormal, negative visibility).
TEST(HizWalk, ReportRowMatchesReportOfPixelByPixel) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const float den = std::numeric_limits<float>::denorm_min();
  const float values[] = {0.0f, -0.0f, 1.0f, 0.5f, -1.0f, nan, inf, -inf, den, -den};
  const int kinds = static_cast<int>(sizeof values / sizeof values[0]);
  for (int width : {1, 15, 16, 17, 31, 32, 33, 100}) {
    std::vector<float> row(4 * static_cast<size_t>(width));
    for (int x = 0; x < width; ++x) {
      row[4 * x + 0] = 0.25f;
      row[4 * x + 1] = 0.75f;
      row[4 * x + 2] = values[x % kinds];
      row[4 * x + 3] = values[(x / kinds + 3 * x) % kinds];
    }
    std::vector<unsigned char> bytes(static_cast<size_t>(width), 7);
    cpu::report_row(row.data(), width, bytes.data());
    int differ = 0, hits = 0, misses = 0, entered = 0;
    for (int x = 0; x < width; ++x) {
      const cpu::Report r = cpu::report_of(row.data() + 4 * x);
      differ += bytes[x] != static_cast<unsigned char>(r);
      hits += r == cpu::Report::Hit;
      misses += r == cpu::Report::Miss;
      entered += r == cpu::Report::Entered;
    }
    EXPECT_EQ(differ, 0) << "width " << width;
    // The values reach every kind of report, so that equal bytes mean something.
    if (width >= 100) EXPECT_TRUE(hits > 0 && misses > 0 && entered > 0 && hits + misses + entered < width) << width;
  }
}

// The byte test the outline search runs on whole rows is the rule it
// stands for: a hit against a miss or a hidden side entered, either way round,
// and nothing against an occluder found late.
TEST(HizWalk, OppositeReportsAreAHitAgainstAMissOrAHiddenSide) {
  using cpu::Report;
  const Report kinds[] = {Report::Miss, Report::Hit, Report::Other, Report::Entered};
  for (Report a : kinds)
    for (Report b : kinds) {
      const bool want = (a == Report::Hit && (b == Report::Miss || b == Report::Entered)) ||
                        (b == Report::Hit && (a == Report::Miss || a == Report::Entered));
      EXPECT_EQ(cpu::opposite_reports(static_cast<unsigned char>(a), static_cast<unsigned char>(b)), want)
          << static_cast<int>(a) << " " << static_cast<int>(b);
    }
}

// A pixel's rays resolved: the hits' share is its visibility and their mean
// its uv; beside a hidden side, the first hit's uv; a miss and a hidden side
// both seen leave the centre's report.
TEST(HizWalk, ResolvedOutlinePixelsShareTheirHits) {
  const float w = 100.0f, h = 50.0f;
  const float centre[4] = {0.500f, 0.500f, 1.0f, 1.0f};
  const float samples[4][4] = {{0.520f, 0.500f, 1.0f, 1.0f},
                               {0.0f, 0.0f, 0.0f, 0.0f},
                               {0.510f, 0.520f, 0.5f, 0.5f},
                               {0.0f, 0.0f, 0.0f, 0.0f}};
  float o[4];
  cpu::resolve_outline(centre, &samples[0][0], 4, w, h, o);
  EXPECT_FLOAT_EQ(o[2], 2.5f / 5.0f);
  EXPECT_FLOAT_EQ(o[3], 2.5f / 5.0f);
  EXPECT_FLOAT_EQ(o[0], (0.500f + 0.520f + 0.5f * 0.510f) / 2.5f);
  cpu::resolve_outline(centre, &samples[0][0], 4, w, h, o, true);
  EXPECT_FLOAT_EQ(o[0], 0.500f);
  EXPECT_FLOAT_EQ(o[1], 0.500f);
  EXPECT_FLOAT_EQ(o[2], 2.5f / 5.0f);
  // Hidden sides in place of the misses: the same share, one hit's uv.
  float entered[4][4];
  std::memcpy(entered, samples, sizeof entered);
  for (int j : {1, 3}) {
    entered[j][0] = entered[j][1] = 0.3f;
    entered[j][2] = 1.0f;
    entered[j][3] = hiz::kEnteredHidden;
  }
  cpu::resolve_outline(centre, &entered[0][0], 4, w, h, o);
  EXPECT_FLOAT_EQ(o[0], 0.500f);
  EXPECT_FLOAT_EQ(o[2], 2.5f / 5.0f);
  // One of each: the centre's report stays (resolved in place, as the marches do).
  entered[3][2] = entered[3][3] = 0.0f;
  std::memcpy(o, centre, sizeof o);
  cpu::resolve_outline(o, &entered[0][0], 4, w, h, o);
  EXPECT_FLOAT_EQ(o[2], 1.0f);
  EXPECT_FLOAT_EQ(o[0], 0.500f);
}

}  // namespace
