// CPU backend vs GL backend, side by side in one run:
//   build/bench/glint_bench_gl [repetitions]
// 1. every stage at 960x540 and 1920x1080 on the shared analytic scene (a
//    mirror floor, two spheres, a wall), each backend given identical inputs;
// 2. the rasterizer at 1k, 100k and 1M triangles (a wavy height field filling
//    a 1920x1080 view).
// Times are the median of the repetitions (default 5) after one warm-up call
// that compiles shaders and allocates textures; GL times include uploading
// the inputs and reading the result back, which is what a caller pays.
// ratio = GL time / CPU time (below 1: GL is faster).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include "../native/tests/analytic_scene.h"
#include "gl/gl_backend.h"
#include "glint/backend.h"
#include "glint/errors.h"
#include "glint/pipeline.h"
#include "meshes.h"

using namespace glint;

namespace {

double median_ms(int reps, const std::function<void()>& f) {
  f();  // warm-up
  std::vector<double> t;
  for (int i = 0; i < reps; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    t.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

void row(const std::string& what, double cpu, double gl) {
  std::printf("%-34s %10.2f %10.2f %8.2f\n", what.c_str(), cpu, gl, gl / cpu);
}

}  // namespace

int main(int argc, char** argv) {
  const int reps = argc > 1 ? std::max(1, std::atoi(argv[1])) : 5;
  std::shared_ptr<Backend> cpu = get_backend("cpu"), gl;
  try {
    gl = get_backend("gl");
  } catch (const BackendUnavailable& e) {
    std::fprintf(stderr, "no GL backend here: %s\n", e.what());
    return 1;
  }
  std::printf("GL:  %s\nCPU: reference backend, all hardware threads\nmedian of %d runs, ms\n\n",
              gl::describe(*gl).c_str(), reps);

  std::printf("%-34s %10s %10s %8s\n", "stage", "cpu", "gl", "gl/cpu");
  for (auto [w, h] : {std::pair{960, 540}, std::pair{1920, 1080}}) {
    const float sky[3] = {0.6f, 0.7f, 0.9f};
    test::Scene s = test::mirror_floor_scene();
    s.planes[0].shininess = 0.6f;  // a glossy floor, so the blur has work
    const test::GBuffer g = test::render(s, perspective(0.9, double(w) / h, 0.1, 100.0), w, h, sky);
    const std::string at = " " + std::to_string(w) + "x" + std::to_string(h);
    PipelineOptions opt;
    const TraceInputs tin{g.position, g.normal, &g.specular, g.projection};
    const Image uv = cpu->trace(tin, opt.trace);
    const Image color = cpu->reflection_color(uv, g.color);
    const Image blurred = cpu->box_blur(color, opt.blur, nullptr);
    const Image refl = cpu->reflection(color, blurred, g.specular);
    TraceOptions linear = opt.trace;
    linear.march = March::Linear;
    linear.steps = 100;  // the book's linear march
    struct Stage {
      const char* name;
      std::function<void(Backend&)> run;
    };
    const std::vector<Stage> stages = {
        {"trace seed", [&](Backend& b) { b.trace(tin, opt.trace); }},
        {"trace linear (100 steps)", [&](Backend& b) { b.trace(tin, linear); }},
        {"reflection_color", [&](Backend& b) { b.reflection_color(uv, g.color); }},
        {"box_blur (17x17)", [&](Backend& b) { b.box_blur(color, opt.blur, nullptr); }},
        {"reflection", [&](Backend& b) { b.reflection(color, blurred, g.specular); }},
        {"combine", [&](Backend& b) { b.combine(g.color, refl, Combine::Over); }},
        {"pipeline (all stages)",
         [&](Backend& b) { run_pipeline(b, {g.position, g.normal, g.specular, g.color, g.projection}, opt); }},
    };
    for (const Stage& st : stages) {
      const double c = median_ms(reps, [&] { st.run(*cpu); });
      const double q = median_ms(reps, [&] { st.run(*gl); });
      row(st.name + at, c, q);
    }
    std::printf("\n");
  }

  std::printf("%-34s %10s %10s %8s\n", "rasterize 1920x1080", "cpu", "gl", "gl/cpu");
  std::vector<Material> mats(2);
  mats[0].specular[0] = mats[0].specular[1] = mats[0].specular[2] = 1.0f;
  mats[0].shininess = kMaxShininess;
  mats[1].shininess = 20.0f;
  const std::vector<Image> maps;
  for (long n : {1000L, 100000L, 1000000L}) {
    const Mesh mesh = bench::height_field(n, -1.5);
    const RasterInputs in{mesh, mats, maps, perspective(0.9, 1920.0 / 1080.0, 0.1, 100.0), 1920, 1080};
    const int r = n >= 1000000 ? std::max(1, reps / 2) : reps;
    const double c = median_ms(r, [&] { cpu->rasterize(in); });
    const double q = median_ms(r, [&] { gl->rasterize(in); });
    row(std::to_string(mesh.triangle_count()) + " triangles", c, q);
  }
  return 0;
}
