// Blur, reflection and combine against plain formulas written out here,
// and the CPU backend's row-parallel loop.
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <vector>

#include "analytic_scene.h"
#include "parallel.h"
#include "glint/errors.h"
#include "glint/composite.h"
#include "glint/pipeline.h"
#include "glint/schema.h"

using namespace glint;

namespace {
Image noise(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  Image img(w, h);
  for (float& v : img.data) v = u(rng);
  return img;
}
}  // namespace

TEST(BoxBlur, MatchesTheBrute2DBoxWithClampToEdge) {
  const int w = 23, h = 17, size = 3;
  Image src = noise(w, h, 7);
  auto cpu = make_cpu_backend(2);
  for (float sep : {1.0f, 2.0f}) {
    BlurOptions o;
    o.size = size;
    o.separation = sep;
    Image out = cpu->box_blur(src, o, nullptr);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 4; ++c) {
          double acc = 0;
          for (int j = -size; j <= size; ++j)
            for (int i = -size; i <= size; ++i) {
              const int xx = std::min(std::max(x + int(i * sep), 0), w - 1);
              const int yy = std::min(std::max(y + int(j * sep), 0), h - 1);
              acc += src.px(xx, yy)[c];
            }
          ASSERT_NEAR(out.px(x, y)[c], acc / ((2 * size + 1) * (2 * size + 1)), 1e-5);
        }
  }
}

TEST(BoxBlur, FractionalSeparationInterpolatesEachTap) {
  // Taps at x + i * 1.5 fall between texels: each is the linear blend of its
  // two neighbours (clamped to the edge), in both axes.
  const int w = 19, h = 13, size = 2;
  const float sep = 1.5f;
  Image src = noise(w, h, 11);
  auto lerp_tap = [&](double px, double py, int c) {
    auto axis = [](double p, int n, int& i0, int& i1, double& a) {
      const double f = std::floor(p);
      a = p - f;
      i0 = std::min(std::max(int(f), 0), n - 1);
      i1 = std::min(std::max(int(f) + 1, 0), n - 1);
    };
    int x0, x1, y0, y1;
    double ax, ay;
    axis(px, w, x0, x1, ax);
    axis(py, h, y0, y1, ay);
    const double bottom = src.px(x0, y0)[c] * (1 - ax) + src.px(x1, y0)[c] * ax;
    const double top = src.px(x0, y1)[c] * (1 - ax) + src.px(x1, y1)[c] * ax;
    return bottom * (1 - ay) + top * ay;
  };
  BlurOptions o;
  o.size = size;
  o.separation = sep;
  Image out = make_cpu_backend(2)->box_blur(src, o, nullptr);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 4; ++c) {
        double acc = 0;
        for (int j = -size; j <= size; ++j)
          for (int i = -size; i <= size; ++i) acc += lerp_tap(x + i * sep, y + j * sep, c);
        ASSERT_NEAR(out.px(x, y)[c], acc / ((2 * size + 1) * (2 * size + 1)), 1e-5) << x << "," << y;
      }
}

TEST(BoxBlur, RegionLeavesTheRestUntouched) {
  Image src = noise(20, 20, 3);
  auto cpu = make_cpu_backend(1);
  const int region[4] = {5, 6, 9, 8};
  Image out = cpu->box_blur(src, BlurOptions{}, region);
  EXPECT_EQ(out.px(0, 0)[0], src.px(0, 0)[0]);
  EXPECT_NE(out.px(6, 7)[0], src.px(6, 7)[0]);
}

TEST(Reflection, MixesByRoughnessAndScalesBySpecularAmount) {
  Image c(1, 1), b(1, 1), s(1, 1);
  for (int k = 0; k < 4; ++k) {
    c.data[k] = 1.0f;
    b.data[k] = 0.0f;
  }
  s.data = {0.3f, 0.6f, 0.9f, 0.25f};  // amount 0.6, roughness 0.75
  auto cpu = make_cpu_backend(1);
  Image r = cpu->reflection(c, b, s);
  EXPECT_NEAR(r.data[0], 0.25f * 0.6f, 1e-6);
  s.data = {0, 0, 0, 1};
  EXPECT_EQ(cpu->reflection(c, b, s).data[0], 0.0f);
}

TEST(Combine, OverAppliesVisibilityOnceSeedTwice) {
  Image base(1, 1), refl(1, 1);
  base.data = {0.2f, 0.2f, 0.2f, 1.0f};
  // A premultiplied reflection: colour 1.0 at alpha 0.5.
  refl.data = {0.5f, 0.5f, 0.5f, 0.5f};
  auto cpu = make_cpu_backend(1);
  EXPECT_NEAR(cpu->combine(base, refl, Combine::Over).data[0], 0.2f * 0.5f + 0.5f, 1e-6);
  EXPECT_NEAR(cpu->combine(base, refl, Combine::Seed).data[0], 0.2f * 0.5f + 0.25f, 1e-6);
  EXPECT_EQ(cpu->combine(base, refl, Combine::Over).data[3], 1.0f);
}

TEST(Pipeline, NoReflectiveSurfaceSkipsEverythingAndReturnsTheBase) {
  test::Scene s = test::mirror_floor_scene();
  for (auto& p : s.planes) p.specular = 0.0f;
  for (auto& sp : s.spheres) sp.specular = 0.0f;
  auto g = test::render(s, perspective(1.0, 1.5, 0.1, 100), 48, 32);
  auto cpu = make_cpu_backend(2);
  PipelineResult r = run_pipeline(*cpu, {g.position, g.normal, g.specular, g.color, g.projection}, {});
  EXPECT_EQ(r.reflective_pixels, 0u);
  EXPECT_EQ(r.layers.at("combined").data, g.color.data);
  for (const auto& t : r.timings)
    if (t.stage != "survey") EXPECT_TRUE(t.skipped) << t.stage;
}

TEST(Pipeline, MirrorOnlySceneSkipsTheBlur) {
  test::Scene s = test::mirror_floor_scene();
  s.spheres[1].specular = 0.0f;  // the only rough reflector
  auto g = test::render(s, perspective(1.0, 1.5, 0.1, 100), 48, 32);
  auto cpu = make_cpu_backend(2);
  PipelineResult r = run_pipeline(*cpu, {g.position, g.normal, g.specular, g.color, g.projection}, {});
  EXPECT_GT(r.reflective_pixels, 0u);
  EXPECT_EQ(r.rough_pixels, 0u);
  for (BlurMode mode : {BlurMode::Cone, BlurMode::Box}) {
    PipelineOptions opt;
    opt.blur_mode = mode;
    PipelineResult r = run_pipeline(*cpu, {g.position, g.normal, g.specular, g.color, g.projection}, opt);
    bool blur_skipped = false;
    for (const auto& t : r.timings)
      if (t.stage == to_string(mode) + std::string("_blur")) blur_skipped = t.skipped;
    EXPECT_TRUE(blur_skipped) << to_string(mode);
  }
}

TEST(Pipeline, NonFiniteShininessIsSmoothWhenDecidingOnTheBlur) {
  // The reflection stage reads a non-finite shininess as 1 (roughness 0), so
  // such a pixel never reads the blur and must not make the pipeline run it.
  test::Scene s = test::mirror_floor_scene();
  s.spheres[1].specular = 0.0f;  // the only rough reflector
  auto g = test::render(s, perspective(1.0, 1.5, 0.1, 100), 48, 32);
  int broken = 0;
  for (int y = 0; y < g.specular.height; ++y)
    for (int x = 0; x < g.specular.width; ++x)
      if (broken < 2 && is_reflective(g.specular.px(x, y)) && g.position.px(x, y)[3] > 0.0f)
        g.specular.px(x, y)[3] = broken++ ? NAN : -INFINITY;
  ASSERT_EQ(broken, 2);
  auto cpu = make_cpu_backend(2);
  PipelineResult r = run_pipeline(*cpu, {g.position, g.normal, g.specular, g.color, g.projection}, {});
  EXPECT_EQ(r.rough_pixels, 0u);
  for (const auto& t : r.timings)
    if (t.stage == "cone_blur" || t.stage == "box_blur") EXPECT_TRUE(t.skipped);
}

// parallel_rows is the CPU backend's only thread machinery; these pin down
// what happens when a body throws or a thread cannot be started.
TEST(ParallelRows, AnExceptionInABodyReachesTheCaller) {
  for (int threads : {1, 4}) {
    std::atomic<int> done{0};
    EXPECT_THROW(parallel_rows(0, 200, threads,
                                    [&](int y) {
                                      if (y == 37) throw std::runtime_error("row 37");
                                      ++done;
                                    }),
                 std::runtime_error)
        << threads << " threads";
    EXPECT_LT(done.load(), 200);
  }
}

TEST(ParallelRows, EveryRowRunsOnceWhenThreadsCannotBeStarted) {
  // In a child process whose address space has no room for another thread
  // stack (8 MiB), starting threads fails with EAGAIN; the rows must still
  // all run, once each, on the threads that exist.
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    std::vector<int> hits(5000, 0);  // allocated before the limit
    long vm_kib = 0;
    if (FILE* f = std::fopen("/proc/self/status", "r")) {
      char line[256];
      while (std::fgets(line, sizeof line, f))
        if (std::sscanf(line, "VmSize: %ld", &vm_kib) == 1) break;
      std::fclose(f);
    }
    if (vm_kib <= 0) _exit(3);
    const rlim_t limit = static_cast<rlim_t>(vm_kib + 2048) * 1024;  // 2 MiB to spare
    const rlimit r{limit, limit};
    if (setrlimit(RLIMIT_AS, &r) != 0) _exit(4);
    parallel_rows(0, 5000, 64, [&](int y) { ++hits[y]; });
    for (int v : hits)
      if (v != 1) _exit(2);
    _exit(0);
  }
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "the child died of signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

// The physical weight of a mirror (shininess 1) seen head on is its F0
// (the Fresnel rim is 0 at N.V = 1: A = 1, B = 0), and at N.V -> 0 it tends to
// 1 (B = 1).
TEST(SpecularWeight, MirrorIsF0HeadOnAndOneAtGrazing) {
  const Mat4 proj = orthographic(2, 2, 0.1, 100);
  Image pos(2, 1), nrm(2, 1), spec(2, 1);
  for (int x = 0; x < 2; ++x) {
    float* p = pos.px(x, 0);
    p[2] = -5.0f;
    p[3] = 1.0f;
    float* s = spec.px(x, 0);
    s[0] = 0.04f, s[1] = 0.5f, s[2] = 1.0f, s[3] = 1.0f;
  }
  nrm.px(0, 0)[2] = 1.0f;  // facing the camera
  nrm.px(1, 0)[0] = 1.0f;  // edge on
  Image w = make_cpu_backend(1)->specular_weight(pos, nrm, spec, proj);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(w.px(0, 0)[c], spec.px(0, 0)[c], 1e-3) << c;
    EXPECT_NEAR(w.px(1, 0)[c], 1.0f, 2e-3) << c;
  }
  EXPECT_NEAR(w.px(0, 0)[3], (0.04f + 0.5f + 1.0f) / 3.0f, 1e-3);
}

// A constant image stays constant under any footprint; a pixel whose hit is
// itself (ray length 0) keeps its colour exactly.
TEST(ConeBlur, ConstantStaysAndContactIsSharp) {
  const int w = 37, h = 21;
  Image col(w, h), uv(w, h), spec(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float* c = col.px(x, y);
      c[0] = 0.25f, c[1] = 0.5f, c[2] = 0.75f, c[3] = 1.0f;
      float* t = uv.px(x, y);
      t[0] = (x + 0.5f + 3.0f * (x % 7)) / w;
      t[1] = (y + 0.5f) / h;
      t[2] = t[3] = 1.0f;
      float* s = spec.px(x, y);
      s[0] = s[1] = s[2] = 0.5f;
      s[3] = 0.2f;
    }
  auto cpu = make_cpu_backend(2);
  Image out = cpu->cone_blur(col, uv, spec, nullptr);
  for (size_t i = 0; i < out.data.size(); ++i) EXPECT_NEAR(out.data[i], col.data[i], 1e-6f);
  col.px(7, 5)[0] = 9.0f;  // x % 7 == 0: ray length 0
  out = cpu->cone_blur(col, uv, spec, nullptr);
  EXPECT_EQ(out.px(7, 5)[0], 9.0f);
}

TEST(Options, WeightingAndBlurNamesRoundTrip) {
  for (Weighting wt : {Weighting::Physical, Weighting::Seed}) EXPECT_EQ(parse_weighting(to_string(wt)), wt);
  for (BlurMode b : {BlurMode::Cone, BlurMode::Box}) EXPECT_EQ(parse_blur_mode(to_string(b)), b);
  EXPECT_THROW(parse_weighting("pbr"), InvalidArgument);
  EXPECT_THROW(parse_blur_mode("gauss"), InvalidArgument);
}

// A uv from outside input can hold any float. Those far off the image must be
// skipped, not converted to int (undefined behaviour the sanitized run reports).
TEST(Composite, UvsFarOffTheImageAreSkipped) {
  const float inf = std::numeric_limits<float>::infinity();
  const float far[] = {1e30f, -1e30f, 3e9f, -3e9f, inf, -inf, std::nanf("")};
  Image pos(4, 4), back_albedo(4, 4, 1.0f), uv(4, 4);
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) pos.px(i, j)[2] = -1.0f, pos.px(i, j)[3] = 1.0f;
  for (size_t k = 0; k < uv.pixel_count(); ++k) {
    float* t = uv.data.data() + k * 4;
    t[0] = far[k % 7];
    t[1] = far[(k + 3) % 7];
    t[2] = 1.0f;
    t[3] = hiz::kEnteredHidden;
  }
  const Image before = uv;
  read_inside_outlines(uv, pos, nullptr, 0.5f, 1);
  for (size_t k = 0; k < uv.data.size(); ++k)
    EXPECT_TRUE(uv.data[k] == before.data[k] || (std::isnan(uv.data[k]) && std::isnan(before.data[k])));
  uint64_t count = 7;
  const Image hidden = hidden_sides(uv, back_albedo, count, 1);
  EXPECT_EQ(count, 0u);
  for (float v : hidden.data) EXPECT_EQ(v, 0.0f);
  int i = -1, j = -1;
  EXPECT_TRUE(pos.texel_at(3.999f, 0.0f, i, j));
  EXPECT_EQ(i, 3);
  EXPECT_EQ(j, 0);
  EXPECT_FALSE(pos.texel_at(4.0f, 0.0f, i, j));
  EXPECT_FALSE(pos.texel_at(-0.001f, 0.0f, i, j));
}
