// The OpenGL backend: the context (made once, shared, usable from any
// thread), the EGL-missing path, shader error locations, size limits, and
// every stage against the CPU reference on the analytic scene. The Python
// suite (tests/python/test_gl_parity.py) runs the wider parity sweep.
//
// Everything that needs a context skips, with the reason, where EGL cannot
// give one; the EGL-missing tests and the log mapping run everywhere.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "analytic_scene.h"
#include "gl/egl_context.h"
#include "glint/marches.h"
#include "gl/gl_backend.h"
#include "gl/program.h"
#include "glint/backend.h"
#include "glint/errors.h"
#include "glint/pipeline.h"

using namespace glint;

namespace {

constexpr double kPi = 3.14159265358979323846;

// The shared GL backend, or a skip naming why there is none.
#define GLINT_REQUIRE_GL(var)                                             \
  std::shared_ptr<Backend> var;                                           \
  try {                                                                   \
    var = get_backend("gl");                                              \
  } catch (const BackendUnavailable& e) {                                 \
    GTEST_SKIP() << "no OpenGL context here: " << e.what();               \
  }

// Share of pixels where every channel of a and b is within tol.
double agreement(const Image& a, const Image& b, float tol_uv, float tol_rest) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  size_t ok = 0;
  for (size_t p = 0; p < a.pixel_count(); ++p) {
    bool same = true;
    for (int c = 0; c < 4; ++c) {
      const float tol = c < 2 ? tol_uv : tol_rest;
      const float x = a.data[p * 4 + c], y = b.data[p * 4 + c];
      same = same && (x == y || std::fabs(x - y) <= tol);
    }
    ok += same;
  }
  return static_cast<double>(ok) / static_cast<double>(a.pixel_count());
}

Image noise(int w, int h, unsigned seed, float lo = 0.0f, float hi = 1.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(lo, hi);
  Image img(w, h);
  for (float& v : img.data) v = u(rng);
  return img;
}

// A rough, partly reflective variant of the shared scene, so that every
// stage has work: the floor is a glossy mirror, the small sphere rough.
test::GBuffer scene(bool ortho, int w, int h) {
  test::Scene s = test::mirror_floor_scene();
  s.planes[0].shininess = 0.6f;
  const Mat4 p = ortho ? orthographic(4.0 * w / h, 4.0, 0.1, 100.0)
                       : perspective(50.0 * kPi / 180.0, double(w) / h, 0.1, 100.0);
  return test::render(s, p, w, h);
}

// The source line after the "GLINT_TEST_ERROR_NEXT_LINE" marker of a file
// under shaders/, read from the source tree so the test follows edits.
int marked_line(const std::string& relative) {
  std::ifstream in(std::string(GLINT_SOURCE_DIR) + "/shaders/" + relative);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n)
    if (line.find("GLINT_TEST_ERROR_NEXT_LINE") != std::string::npos) return n + 1;
  ADD_FAILURE() << "no marker in shaders/" << relative;
  return -1;
}

}  // namespace

// --- context ---------------------------------------------------------------------

TEST(GlContext, IsMadeOnceAndSharedByGlAndAuto) {
  GLINT_REQUIRE_GL(gl);
  EXPECT_EQ(gl->name(), "gl");
  EXPECT_EQ(get_backend("gl").get(), gl.get());
  EXPECT_EQ(get_backend("auto").get(), gl.get());
  const std::string what = gl::describe(*gl);
  EXPECT_NE(what.find("EGL"), std::string::npos) << what;
  EXPECT_NE(what.find("OpenGL"), std::string::npos) << what;
  std::printf("GL backend: %s\n", what.c_str());
}

TEST(GlContext, MissingEglLibraryIsAClearError) {
  const std::string path = "/nonexistent/glint-test/libEGL.so.1";
  try {
    gl::create_gl_backend(path);
    FAIL() << "expected BackendUnavailable";
  } catch (const BackendUnavailable& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("EGL library"), std::string::npos) << msg;
    EXPECT_NE(msg.find("GLINT_EGL_LIBRARY"), std::string::npos) << msg;
  }
}

TEST(GlContext, ALibraryThatIsNotEglNamesTheMissingFunction) {
  try {
    gl::create_gl_backend("libm.so.6");
    FAIL() << "expected BackendUnavailable";
  } catch (const BackendUnavailable& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("eglGetProcAddress"), std::string::npos) << msg;
    EXPECT_NE(msg.find("libm.so.6"), std::string::npos) << msg;
  }
}

TEST(GlContext, SeveralContextsCanLiveAndDieInOneProcess) {
  GLINT_REQUIRE_GL(shared);
  // A second, private context: made, used and freed while the shared one
  // stays usable.
  const test::GBuffer g = scene(false, 32, 24);
  Image first;
  {
    auto own = gl::create_gl_backend(gl::egl_library_path());
    first = own->combine(g.color, g.color, Combine::Over);
  }
  const Image again = shared->combine(g.color, g.color, Combine::Over);
  EXPECT_EQ(first.data, again.data);
}

TEST(GlContext, CallsFromManyThreadsAreSerializedAndCorrect) {
  GLINT_REQUIRE_GL(gl);
  const test::GBuffer g = scene(false, 64, 48);
  auto cpu = make_cpu_backend(1);
  const Image expected = cpu->trace(TraceInputs{g.position, g.normal, nullptr, g.projection}, TraceOptions{});
  std::atomic<int> mismatches{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&] {
      for (int i = 0; i < 3; ++i) {
        const Image out = gl->trace(TraceInputs{g.position, g.normal, nullptr, g.projection}, TraceOptions{});
        if (agreement(out, expected, 1e-4f, 1e-3f) < 0.99) ++mismatches;
      }
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(mismatches.load(), 0);
}

// --- shaders ---------------------------------------------------------------------

TEST(GlShaders, LogLocationsAreMappedToFilesAndLines) {
  // Number 0 is the entry's #version line; the others are the embed list's order.
  const std::string mesa = gl::map_shader_log("0:7(3): error: x\n1:12(5): error: `y' undeclared\n", "combine.frag");
  EXPECT_NE(mesa.find("shaders/combine.frag:7(3): error: x"), std::string::npos) << mesa;
  EXPECT_NE(mesa.find("shaders/common.glsl:12(5): error: `y' undeclared"), std::string::npos) << mesa;
  const std::string nvidia = gl::map_shader_log("1(12) : error C1008: undefined variable \"y\"", "a.frag");
  EXPECT_NE(nvidia.find("shaders/common.glsl:12 : error C1008"), std::string::npos) << nvidia;
  const std::string amd = gl::map_shader_log("ERROR: 1:12: 'y' : undeclared identifier", "a.frag");
  EXPECT_NE(amd.find("ERROR: shaders/common.glsl:12: 'y'"), std::string::npos) << amd;
  // Text without a location is left alone.
  EXPECT_EQ(gl::map_shader_log("error: vec4(1.0) expected", "a.frag"), "error: vec4(1.0) expected\n");
}

// shaders/testing/, embedded into this test alone (native/tests/CMakeLists.txt).
namespace glint::gl::test_shaders {
const EmbeddedShader* find_embedded_shader(const std::string& name);
const char* embedded_file_name(int number);
}  // namespace glint::gl::test_shaders

namespace {

void compile_test_shader(Backend& backend, const std::string& entry) {
  const gl::EmbeddedShader* s = gl::test_shaders::find_embedded_shader(entry);
  ASSERT_NE(s, nullptr) << entry;
  gl::compile_for_test(backend, entry, s->source, &gl::test_shaders::embedded_file_name);
}

}  // namespace

TEST(GlShaders, CompileErrorNamesTheFileAndLineAfterAnInclude) {
  GLINT_REQUIRE_GL(gl);
  const int line = marked_line("testing/broken.frag");
  try {
    compile_test_shader(*gl, "testing/broken.frag");
    FAIL() << "the deliberately broken shader compiled";
  } catch (const Error& e) {
    const std::string msg = e.what();
    const std::string where = "shaders/testing/broken.frag:" + std::to_string(line);
    EXPECT_NE(msg.find(where), std::string::npos) << "expected " << where << " in:\n" << msg;
    EXPECT_NE(msg.find("undeclared_on_purpose"), std::string::npos) << msg;
  }
}

TEST(GlShaders, CompileErrorInAnIncludedFileNamesThatFile) {
  GLINT_REQUIRE_GL(gl);
  const int line = marked_line("testing/broken_include.glsl");
  try {
    compile_test_shader(*gl, "testing/broken_in_include.frag");
    FAIL() << "the deliberately broken shader compiled";
  } catch (const Error& e) {
    const std::string msg = e.what();
    const std::string where = "shaders/testing/broken_include.glsl:" + std::to_string(line);
    EXPECT_NE(msg.find(where), std::string::npos) << "expected " << where << " in:\n" << msg;
  }
}

TEST(GlShaders, EveryPassCompilesAndLinks) {
  GLINT_REQUIRE_GL(gl);
  for (const char* f : {"reflection_color.frag", "box_blur.frag", "reflection.frag", "combine.frag"})
    EXPECT_NO_THROW(gl::compile_for_test(*gl, f)) << f;
  // Every march's GL program, from the table: a new march's is compiled too.
  for (const MarchInfo& m : march_table())
    if (m.gl_program) EXPECT_NO_THROW(gl::compile_for_test(*gl, m.gl_program)) << m.gl_program;
}

// --- stages against the CPU reference ---------------------------------------------

TEST(GlParity, TraceMatchesTheCpuOnPerspectiveAndOrthographicScenes) {
  GLINT_REQUIRE_GL(gl);
  auto cpu = make_cpu_backend();
  for (bool ortho : {false, true}) {
    const test::GBuffer g = scene(ortho, 160, 90);
    for (const MarchInfo& info : march_table()) {
      if (info.needs_mesh) continue;
      const March m = info.id;
      TraceOptions o;
      o.march = m;
      for (bool gated : {false, true}) {
        const TraceInputs in{g.position, g.normal, gated ? &g.specular : nullptr, g.projection};
        const Image a = cpu->trace(in, o), b = gl->trace(in, o);
        const double share = agreement(a, b, 1e-4f, 1e-3f);
        std::printf("trace %s %s%s: %.4f of pixels agree\n", ortho ? "ortho" : "persp", to_string(m),
                    gated ? " (specular-gated)" : "", share);
        EXPECT_GE(share, 0.99);
      }
    }
  }
}

TEST(GlParity, HizAntialiasedOutlinesMatchTheCpu) {
  // The outline pixels' extra rays (march_hiz.cpp, cpu/outline.cpp) on the GL passes, with
  // every pixel's own ray and with the reuse of rays. The pixels they change
  // are a few percent of the frame: compared on their own too, so that a GL
  // trace that skipped them could not pass on the whole frame's share. The
  // perspective view without its specular buffer (every surface a mirror:
  // outlines everywhere), the orthographic one with it (glossy surfaces,
  // whose outlines the cone blur spreads: few or no extra rays, on both).
  GLINT_REQUIRE_GL(gl);
  auto cpu = make_cpu_backend();
  for (bool ortho : {false, true}) {
    const test::GBuffer g = scene(ortho, 160, 90);
    const TraceInputs in{g.position, g.normal, ortho ? &g.specular : nullptr, g.projection};
    for (float resolution : {1.0f, 0.3f}) {
      for (int antialias : {1, 4}) {
        TraceOptions o;
        o.march = March::Hiz;
        o.resolution = resolution;
        const Image plain = cpu->trace(in, o);
        o.antialias = antialias;
        const Image a = cpu->trace(in, o), b = gl->trace(in, o);
        std::vector<size_t> changed_px;
        for (size_t p = 0; p < a.pixel_count(); ++p)
          for (int c = 0; c < 4; ++c)
            if (a.data[p * 4 + c] != plain.data[p * 4 + c]) {
              changed_px.push_back(p);
              break;
            }
        // The changed pixels, as one row.
        Image ca(static_cast<int>(changed_px.size()), 1), cb(ca.width, 1);
        for (size_t e = 0; e < changed_px.size(); ++e)
          for (int c = 0; c < 4; ++c) {
            ca.data[e * 4 + c] = a.data[changed_px[e] * 4 + c];
            cb.data[e * 4 + c] = b.data[changed_px[e] * 4 + c];
          }
        const double share = agreement(a, b, 1e-4f, 1e-3f), changed = agreement(ca, cb, 1e-4f, 1e-3f);
        std::printf("trace hiz %s resolution %.1f antialias %d: %.4f of pixels agree, %.4f of the %d changed\n",
                    ortho ? "ortho" : "persp", resolution, antialias, share, changed, ca.width);
        if (!ortho) EXPECT_GE(ca.width, 50) << "the outlines should change some pixels";
        EXPECT_GE(share, 0.99);
        if (ca.width > 0) EXPECT_GE(changed, 0.99);
      }
    }
  }
}

TEST(GlParity, NonFiniteInputsAreTreatedAsNothingSeenLikeOnTheCpu) {
  GLINT_REQUIRE_GL(gl);
  auto cpu = make_cpu_backend(1);
  test::GBuffer g = scene(false, 64, 48);
  const float nan = std::nanf(""), inf = INFINITY;
  g.position.px(10, 5)[0] = nan;
  g.position.px(30, 6)[2] = -inf;
  g.normal.px(31, 7)[1] = nan;
  g.color.px(20, 20)[0] = inf;
  g.color.px(21, 21)[1] = nan;
  const TraceInputs in{g.position, g.normal, nullptr, g.projection};
  const Image a = cpu->trace(in, TraceOptions{}), b = gl->trace(in, TraceOptions{});
  for (const Image* img : {&a, &b}) {
    for (float v : img->data) ASSERT_TRUE(std::isfinite(v));
    EXPECT_EQ(img->px(10, 5)[2], 0.0f);
    EXPECT_EQ(img->px(31, 7)[2], 0.0f);
  }
  EXPECT_GE(agreement(a, b, 1e-4f, 1e-3f), 0.99);
  const Image ca = cpu->reflection_color(a, g.color), cb = gl->reflection_color(a, g.color);
  for (float v : cb.data) ASSERT_TRUE(std::isfinite(v));
  EXPECT_GE(agreement(ca, cb, 1e-4f, 1e-4f), 0.999);
}

TEST(GlParity, EveryOtherStageMatchesTheCpuOnIdenticalInputs) {
  GLINT_REQUIRE_GL(gl);
  auto cpu = make_cpu_backend();
  const test::GBuffer g = scene(false, 160, 90);
  const Image uv = cpu->trace(TraceInputs{g.position, g.normal, &g.specular, g.projection}, TraceOptions{});
  auto check = [](const char* stage, const Image& a, const Image& b) {
    const double share = agreement(a, b, 1e-4f, 1e-4f);
    std::printf("%s: %.5f of pixels agree\n", stage, share);
    EXPECT_GE(share, 0.999) << stage;
  };
  const Image color = cpu->reflection_color(uv, g.color);
  check("reflection_color", color, gl->reflection_color(uv, g.color));
  // The colour lookup at a uv texture of another size than the colour.
  const Image small_uv = noise(37, 23, 5, -0.2f, 1.2f);
  check("reflection_color (37x23 uv on 160x90 colour)", cpu->reflection_color(small_uv, g.color),
        gl->reflection_color(small_uv, g.color));
  for (float sep : {1.0f, 1.7f, 3.0f}) {
    BlurOptions o;
    o.size = 4;
    o.separation = sep;
    const int region[4] = {20, 10, 120, 60};
    check("box_blur (whole image)", cpu->box_blur(color, o, nullptr), gl->box_blur(color, o, nullptr));
    check("box_blur (region)", cpu->box_blur(color, o, region), gl->box_blur(color, o, region));
  }
  const Image blurred = cpu->box_blur(color, BlurOptions{}, nullptr);
  const Image refl = cpu->reflection(color, blurred, g.specular);
  check("reflection", refl, gl->reflection(color, blurred, g.specular));
  check("combine over", cpu->combine(g.color, refl, Combine::Over), gl->combine(g.color, refl, Combine::Over));
  check("combine seed", cpu->combine(g.color, refl, Combine::Seed), gl->combine(g.color, refl, Combine::Seed));
}

TEST(GlParity, ResultsStayRightWhenTheImageSizeChangesBetweenCalls) {
  // Textures are kept between calls and reallocated on a size change: a
  // reallocation must not disturb the inputs already bound for the pass.
  GLINT_REQUIRE_GL(gl);
  auto cpu = make_cpu_backend(1);
  for (auto [w, h] : {std::pair{41, 29}, std::pair{64, 64}, std::pair{41, 29}, std::pair{17, 70}}) {
    const test::GBuffer g = scene(false, w, h);
    const TraceInputs in{g.position, g.normal, &g.specular, g.projection};
    EXPECT_GE(agreement(cpu->trace(in, TraceOptions{}), gl->trace(in, TraceOptions{}), 1e-4f, 1e-3f), 0.99);
    const Image src = noise(w, h, 11);
    BlurOptions o;
    o.size = 3;
    EXPECT_GE(agreement(cpu->box_blur(src, o, nullptr), gl->box_blur(src, o, nullptr), 1e-4f, 1e-4f), 0.999);
  }
}

TEST(GlParity, WholePipelineMatchesTheCpu) {
  GLINT_REQUIRE_GL(gl);
  auto cpu = make_cpu_backend();
  const test::GBuffer g = scene(true, 128, 96);
  PipelineInputs in{g.position, g.normal, g.specular, g.color, g.projection};
  const PipelineResult a = run_pipeline(*cpu, in, PipelineOptions{});
  const PipelineResult b = run_pipeline(*gl, in, PipelineOptions{});
  for (const auto& name : pipeline_layer_names()) {
    const bool uv = name == "uv";
    EXPECT_GE(agreement(a.layers.at(name), b.layers.at(name), 1e-4f, uv ? 1e-3f : 1e-4f), uv ? 0.99 : 0.999)
        << name;
  }
}

// --- the rasterizer ---------------------------------------------------------------

namespace {

// A UV sphere over a tessellated floor, in view space, two materials.
Mesh sphere_and_floor(int segments) {
  Mesh m;
  auto push = [&](const double p[3][3], const double n[3][3], int mat) {
    for (int v = 0; v < 3; ++v)
      for (int k = 0; k < 3; ++k) {
        m.positions.push_back(static_cast<float>(p[v][k]));
        m.normals.push_back(static_cast<float>(n[v][k]));
      }
    m.material.push_back(mat);
  };
  const double c[3] = {0.3, -0.2, -5.0}, r = 1.1;
  auto sph = [&](int i, int j, double p[3], double n[3]) {
    const double th = kPi * j / segments, ph = 2 * kPi * i / (2 * segments);
    n[0] = std::sin(th) * std::cos(ph);
    n[1] = std::cos(th);
    n[2] = std::sin(th) * std::sin(ph);
    for (int k = 0; k < 3; ++k) p[k] = c[k] + r * n[k];
  };
  for (int i = 0; i < 2 * segments; ++i)
    for (int j = 0; j < segments; ++j) {
      double p[4][3], n[4][3];
      sph(i, j, p[0], n[0]);
      sph(i + 1, j, p[1], n[1]);
      sph(i + 1, j + 1, p[2], n[2]);
      sph(i, j + 1, p[3], n[3]);
      const double t0[3][3] = {{p[0][0], p[0][1], p[0][2]}, {p[1][0], p[1][1], p[1][2]}, {p[2][0], p[2][1], p[2][2]}};
      const double n0[3][3] = {{n[0][0], n[0][1], n[0][2]}, {n[1][0], n[1][1], n[1][2]}, {n[2][0], n[2][1], n[2][2]}};
      const double t1[3][3] = {{p[0][0], p[0][1], p[0][2]}, {p[2][0], p[2][1], p[2][2]}, {p[3][0], p[3][1], p[3][2]}};
      const double n1[3][3] = {{n[0][0], n[0][1], n[0][2]}, {n[2][0], n[2][1], n[2][2]}, {n[3][0], n[3][1], n[3][2]}};
      push(t0, n0, 0);
      push(t1, n1, 0);
    }
  const int cells = 12;
  for (int i = 0; i < cells; ++i)
    for (int j = 0; j < cells; ++j) {
      const double x0 = -6 + 12.0 * i / cells, x1 = -6 + 12.0 * (i + 1) / cells;
      const double z0 = -1 - 20.0 * j / cells, z1 = -1 - 20.0 * (j + 1) / cells;
      // Sloping up as it recedes (a floor seen from above), so that an
      // orthographic camera looking down -Z does not see it edge-on.
      const double y0 = -2.5 - 0.2 * z0, y1 = -2.5 - 0.2 * z1;
      const double s = 1.0 / std::sqrt(1.04);
      const double up[3][3] = {{0, s, 0.2 * s}, {0, s, 0.2 * s}, {0, s, 0.2 * s}};
      const double a[3][3] = {{x0, y0, z0}, {x1, y0, z0}, {x1, y1, z1}};
      const double b[3][3] = {{x0, y0, z0}, {x1, y1, z1}, {x0, y1, z1}};
      push(a, up, 1);
      push(b, up, 1);
    }
  return m;
}

}  // namespace

TEST(GlRaster, GBuffersMatchTheCpuReference) {
  GLINT_REQUIRE_GL(gl);
  auto cpu = make_cpu_backend();
  const Mesh mesh = sphere_and_floor(24);
  std::vector<Material> mats(2);
  mats[0].specular[0] = mats[0].specular[1] = mats[0].specular[2] = 0.3f;
  mats[0].shininess = 40.0f;
  mats[1].specular[0] = mats[1].specular[1] = mats[1].specular[2] = 1.0f;
  mats[1].shininess = kMaxShininess;
  const std::vector<Image> maps;
  for (bool ortho : {false, true}) {
    const int w = 160, h = 90;
    const Mat4 p = ortho ? orthographic(4.0 * w / h, 4.0, 0.1, 100.0)
                         : perspective(60.0 * kPi / 180.0, double(w) / h, 0.1, 100.0);
    const RasterInputs in{mesh, mats, maps, p, w, h};
    const GBufferImages a = cpu->rasterize(in), b = gl->rasterize(in);
    size_t same_cover = 0, both = 0, close = 0, covered = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const float* pa = a.position.px(x, y);
        const float* pb = b.position.px(x, y);
        const bool ca = pa[3] > 0, cb = pb[3] > 0;
        covered += ca;
        same_cover += ca == cb;
        if (!(ca && cb)) continue;
        ++both;
        float err = 0, scale = 1;
        for (int k = 0; k < 3; ++k) {
          err = std::fmax(err, std::fabs(pa[k] - pb[k]));
          scale = std::fmax(scale, std::fabs(pa[k]));
        }
        bool ok = err <= 1e-4f * scale;
        for (int k = 0; k < 3; ++k) ok = ok && std::fabs(a.normal.px(x, y)[k] - b.normal.px(x, y)[k]) <= 1e-3f;
        for (int k = 0; k < 4; ++k) ok = ok && a.specular.px(x, y)[k] == b.specular.px(x, y)[k];
        close += ok;
      }
    const double cover_share = double(same_cover) / (w * h), attr_share = double(close) / both;
    std::printf("raster %s: %zu covered, coverage agrees on %.4f, attributes on %.4f\n",
                ortho ? "ortho" : "persp", covered, cover_share, attr_share);
    EXPECT_GT(covered, size_t(w * h / 4));
    EXPECT_GE(cover_share, 0.995);
    EXPECT_GE(attr_share, 0.995);
  }
}

TEST(GlRaster, BackFacesGetNormalsTowardTheEye) {
  GLINT_REQUIRE_GL(gl);
  // One clockwise (back-facing) triangle whose corner normals point away.
  Mesh m;
  m.positions = {-1, -1, -3, -1, 1, -3, 1, -1, -3};
  m.normals = {0, 0, -1, 0, 0, -1, 0, 0, -1};
  m.material = {0};
  const std::vector<Material> mats(1);
  const std::vector<Image> maps;
  const RasterInputs in{m, mats, maps, perspective(kPi / 2, 1.0, 0.1, 10.0), 16, 16};
  const GBufferImages g = gl->rasterize(in);
  const float* n = g.normal.px(5, 5);
  ASSERT_GT(g.position.px(5, 5)[3], 0.0f);
  EXPECT_NEAR(n[2], 1.0f, 1e-6f);
  EXPECT_FLOAT_EQ(g.position.px(5, 5)[2], -3.0f);
  // Unseen pixels are all zero.
  for (int k = 0; k < 4; ++k) EXPECT_EQ(g.position.px(15, 15)[k], 0.0f);
}

TEST(GlRaster, NormalMapsMatchTheCpuReference) {
  GLINT_REQUIRE_GL(gl);
  auto cpu = make_cpu_backend(1);
  // A floor quad seen at an angle, with a bumpy tangent-space normal map.
  Mesh m;
  m.positions = {-2, -1, -2, 2, -1, -2, 2, -1, -8, -2, -1, -2, 2, -1, -8, -2, -1, -8};
  m.normals = {0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0};
  m.uvs = {0, 0, 2, 0, 2, 3, 0, 0, 2, 3, 0, 3};
  m.tangents = {1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, -1, 1, 0, 0, -1, 1, 0, 0, -1};
  // The second triangle has a material without a map: two draws, the second
  // one starting at triangle 1, which the material lookup must account for.
  m.material = {0, 1};
  std::vector<Material> mats(2);
  mats[0].normal_map = 0;
  mats[0].specular[0] = 0.5f;
  mats[1].specular[1] = 0.25f;
  mats[1].shininess = 64.0f;
  Image map(16, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      const float nx = 0.4f * std::sin(x * 0.8f), ny = 0.3f * std::cos(y * 0.6f);
      const float nz = std::sqrt(1.0f - nx * nx - ny * ny);
      float* p = map.px(x, y);
      p[0] = nx * 0.5f + 0.5f;
      p[1] = ny * 0.5f + 0.5f;
      p[2] = nz * 0.5f + 0.5f;
      p[3] = 1.0f;
    }
  const std::vector<Image> maps{map};
  const RasterInputs in{m, mats, maps, perspective(kPi / 3, 4.0 / 3.0, 0.1, 50.0), 64, 48};
  const GBufferImages a = cpu->rasterize(in), b = gl->rasterize(in);
  size_t both = 0, close = 0, bent = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      if (!(a.position.px(x, y)[3] > 0 && b.position.px(x, y)[3] > 0)) continue;
      ++both;
      bent += std::fabs(b.normal.px(x, y)[1] - 1.0f) > 0.02f;  // the map did something
      for (int k = 0; k < 4; ++k) ASSERT_EQ(a.specular.px(x, y)[k], b.specular.px(x, y)[k]) << x << "," << y;
      float err = 0;
      for (int k = 0; k < 3; ++k) err = std::fmax(err, std::fabs(a.normal.px(x, y)[k] - b.normal.px(x, y)[k]));
      close += err <= 1e-3f;
    }
  ASSERT_GT(both, 500u);
  EXPECT_GT(bent, both / 4);
  // Filtering precision differs (the CPU in double, GL in float), hence 1e-3.
  EXPECT_GE(double(close) / both, 0.995);
}

namespace {

// Closed axis-aligned boxes, faces wound counter-clockwise seen from outside,
// one material each.
void push_box(Mesh& m, const double lo[3], const double hi[3], int mat) {
  for (int a = 0; a < 3; ++a)
    for (int side = 0; side < 2; ++side) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      const double bc[4][2] = {{lo[b], lo[c]}, {hi[b], lo[c]}, {hi[b], hi[c]}, {lo[b], hi[c]}};
      double q[4][3];
      for (int k = 0; k < 4; ++k) {
        const int from = side ? k : 3 - k;  // e_b x e_c = e_a: backwards on the -a face
        q[k][a] = side ? hi[a] : lo[a];
        q[k][b] = bc[from][0];
        q[k][c] = bc[from][1];
      }
      const int order[2][3] = {{0, 1, 2}, {0, 2, 3}};
      for (const auto& t : order) {
        for (int v = 0; v < 3; ++v)
          for (int k = 0; k < 3; ++k) {
            m.positions.push_back(static_cast<float>(q[t[v]][k]));
            m.normals.push_back(k == a ? (side ? 1.0f : -1.0f) : 0.0f);
          }
        m.material.push_back(mat);
      }
    }
}

}  // namespace

// The back layer's albedo is a copy of a material's, so where both backends
// find a back surface they give the same bits. Three boxes of three
// materials overlapping on screen; the albedo asked for on every other call,
// so the back pass's targets change their colour count both ways.
TEST(GlRaster, BackAlbedoMatchesTheCpuBitForBit) {
  GLINT_REQUIRE_GL(gl);
  auto cpu = make_cpu_backend(2);
  Mesh m;
  const double lo[3][3] = {{-3, -2, -12}, {-0.8, -0.6, -6}, {0.2, -1.5, -8}};
  const double hi[3][3] = {{3, 2, -9}, {0.6, 0.9, -4.5}, {1.7, 0.2, -6.5}};
  for (int k = 0; k < 3; ++k) push_box(m, lo[k], hi[k], k);
  std::vector<Material> mats(3);
  const float albedo[3][3] = {{0.9f, 0.2f, 0.1f}, {0.05f, 0.7f, 0.3f}, {0.25f, 0.25f, 1.5f}};
  for (int k = 0; k < 3; ++k)
    for (int c = 0; c < 3; ++c) mats[k].albedo[c] = albedo[k][c];
  const std::vector<Image> maps;
  const int w = 96, h = 64;
  RasterInputs in{m, mats, maps, perspective(50.0 * kPi / 180.0, double(w) / h, 0.1, 100.0), w, h};
  in.back_layer = true;
  for (bool with_albedo : {false, true, false, true}) {
    in.back_albedo = with_albedo;
    const GBufferImages a = cpu->rasterize(in), b = gl->rasterize(in);
    if (!with_albedo) {
      EXPECT_TRUE(b.back_albedo.empty());
      EXPECT_FALSE(b.back_position.empty());
      continue;
    }
    ASSERT_EQ(b.back_albedo.width, w);
    ASSERT_EQ(b.back_albedo.height, h);
    size_t both = 0, differ = 0;
    int seen[3] = {0, 0, 0};
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const bool ca = a.back_position.px(x, y)[3] > 0, cb = b.back_position.px(x, y)[3] > 0;
        differ += ca != cb;
        const float* pa = a.back_albedo.px(x, y);
        const float* pb = b.back_albedo.px(x, y);
        if (!cb) {
          for (int c = 0; c < 4; ++c) ASSERT_EQ(pb[c], 0.0f) << x << "," << y;
          continue;
        }
        ASSERT_EQ(pb[3], 1.0f) << x << "," << y;
        if (!ca) continue;
        ++both;
        for (int c = 0; c < 4; ++c) ASSERT_EQ(pa[c], pb[c]) << x << "," << y << " channel " << c;
        for (int k = 0; k < 3; ++k) seen[k] += pb[0] == albedo[k][0];
      }
    // The back test compares against the front in float on the GPU, in
    // double on the CPU: a grazing silhouette pixel may go either way.
    EXPECT_LE(differ, size_t(w * h / 200));
    EXPECT_GT(both, size_t(w * h / 8));
    std::printf("back albedo: %zu pixels on both, back coverage differs on %zu\n", both, differ);
    for (int k = 0; k < 3; ++k) EXPECT_GT(seen[k], 20) << "material " << k;
  }
}

// --- limits ------------------------------------------------------------------------

TEST(GlLimits, LargerThanTheGlTextureLimitIsAClearError) {
  GLINT_REQUIRE_GL(gl);
  // One row wider than GL_MAX_TEXTURE_SIZE (16384 on llvmpipe) but within
  // Glint's own limit: cheap, and exactly the path a too-large frame takes.
  const int w = kMaxImageSide;
  const Image base(w, 1, 0.5f), refl(w, 1, 0.0f);
  try {
    const Image out = gl->combine(base, refl, Combine::Over);
    EXPECT_EQ(out.px(w - 1, 0)[0], 0.5f);  // this GL allows it: then it must be right
  } catch (const BackendUnavailable&) {
    FAIL() << "a size limit is not a missing backend";
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(std::to_string(w) + "x1"), std::string::npos) << msg;
    EXPECT_NE(msg.find("GL_MAX_TEXTURE_SIZE"), std::string::npos) << msg;
    EXPECT_NE(msg.find("MiB"), std::string::npos) << msg;
  }
}

TEST(GlLimits, EightKEitherWorksOrFailsWithAClearOutOfMemoryError) {
  GLINT_REQUIRE_GL(gl);
  const int w = 7680, h = 4320;
  Image base, refl;
  try {
    base = Image(w, h, 0.25f);
    refl = Image(w, h, 0.0f);
  } catch (const std::bad_alloc&) {
    GTEST_SKIP() << "not enough host memory for two 8K images";
  }
  refl.px(w - 1, h - 1)[0] = 0.5f;
  refl.px(w - 1, h - 1)[3] = 0.5f;
  try {
    const Image out = gl->combine(base, refl, Combine::Over);
    EXPECT_FLOAT_EQ(out.px(0, 0)[0], 0.25f);
    EXPECT_FLOAT_EQ(out.px(w - 1, h - 1)[0], 0.25f * 0.5f + 0.5f);
    EXPECT_FLOAT_EQ(out.px(w - 1, h - 1)[3], 0.25f);
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("7680x4320"), std::string::npos) << msg;
    EXPECT_NE(msg.find("MiB"), std::string::npos) << msg;
  }
}
