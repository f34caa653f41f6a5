// Per-stage cost of the CPU backend on the shared analytic scene:
//   build/bench/glint_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <map>

#include "../native/tests/analytic_scene.h"
#include "glint/pipeline.h"

using namespace glint;

namespace {

const test::GBuffer& scene(int w, int h) {
  static std::map<std::pair<int, int>, test::GBuffer> cache;
  auto key = std::make_pair(w, h);
  auto it = cache.find(key);
  if (it == cache.end()) {
    const float sky[3] = {0.6f, 0.7f, 0.9f};
    it = cache.emplace(key, test::render(test::mirror_floor_scene(),
                                         perspective(0.9, double(w) / h, 0.1, 100.0), w, h, sky))
             .first;
  }
  return it->second;
}

void BM_Stage(benchmark::State& state, const std::string& stage) {
  const int w = int(state.range(0)), h = int(state.range(1));
  const auto& g = scene(w, h);
  auto cpu = make_cpu_backend(0);
  PipelineOptions opt;
  Image uv = cpu->trace({g.position, g.normal, &g.specular, g.projection}, opt.trace);
  Image color = cpu->reflection_color(uv, g.color);
  Image blurred = cpu->box_blur(color, opt.blur, nullptr);
  Image refl = cpu->reflection(color, blurred, g.specular);
  for (auto _ : state) {
    if (stage == "trace") benchmark::DoNotOptimize(cpu->trace({g.position, g.normal, &g.specular, g.projection}, opt.trace));
    if (stage == "reflection_color") benchmark::DoNotOptimize(cpu->reflection_color(uv, g.color));
    if (stage == "box_blur") benchmark::DoNotOptimize(cpu->box_blur(color, opt.blur, nullptr));
    if (stage == "reflection") benchmark::DoNotOptimize(cpu->reflection(color, blurred, g.specular));
    if (stage == "combine") benchmark::DoNotOptimize(cpu->combine(g.color, refl, opt.combine));
    if (stage == "pipeline")
      benchmark::DoNotOptimize(run_pipeline(*cpu, {g.position, g.normal, g.specular, g.color, g.projection}, opt));
  }
}

}  // namespace

#define GLINT_STAGE(name)                                                                  \
  BENCHMARK_CAPTURE(BM_Stage, name, std::string(#name))                                    \
      ->Args({960, 540})                                                                   \
      ->Args({1920, 1080})                                                                 \
      ->Unit(benchmark::kMillisecond)                                                      \
      ->UseRealTime()

GLINT_STAGE(trace);
GLINT_STAGE(reflection_color);
GLINT_STAGE(box_blur);
GLINT_STAGE(reflection);
GLINT_STAGE(combine);
GLINT_STAGE(pipeline);

BENCHMARK_MAIN();
