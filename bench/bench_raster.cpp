// CPU rasterizer cost against triangle count at 1920 x 1080 (the Python call,
// CPU and GL side by side, is bench/raster_bench.py):
//   build/bench/glint_bench_raster --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
// "Grid": a wavy height field filling the view (depth complexity about 1,
// every triangle the same size: the shape of a real tessellated mesh).
// "Soup": random triangles scattered through the frustum, about 9 pixels
// across (6 pixels of area) whatever their depth, so 1M of them cover the
// screen about 3 times over; some cross the screen edges and get clipped.
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <random>

#include "glint/raster.h"
#include "glint/stages.h"
#include "meshes.h"

using namespace glint;

namespace {

constexpr int kWidth = 1920, kHeight = 1080;

Mat4 camera() { return perspective(0.9, double(kWidth) / kHeight, 0.1, 100.0); }

Mesh soup_mesh(long triangles) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Mesh m;
  for (long t = 0; t < triangles; ++t) {
    const float z = -0.2f - 9.9f * (u(rng) * 0.5f + 0.5f);
    const float cx = u(rng) * -z * 0.85f, cy = u(rng) * -z * 0.47f;
    const float s = 0.004f * -z;  // corners within +-4.5 pixels of the centre at any depth
    for (int v = 0; v < 3; ++v) {
      m.positions.push_back(cx + s * u(rng));
      m.positions.push_back(cy + s * u(rng));
      m.positions.push_back(z + s * u(rng));
      m.normals.push_back(0.0f), m.normals.push_back(0.0f), m.normals.push_back(1.0f);
    }
    m.material.push_back(static_cast<int32_t>(t % 2));
  }
  return m;
}

const Mesh& cached(bool grid, long triangles) {
  static std::map<std::pair<bool, long>, Mesh> cache;
  auto key = std::make_pair(grid, triangles);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, grid ? bench::height_field(triangles) : soup_mesh(triangles)).first;
  return it->second;
}

void BM_Rasterize(benchmark::State& state, bool grid) {
  const Mesh& mesh = cached(grid, state.range(0));
  std::vector<Material> mats(2);
  mats[0].specular[0] = mats[0].specular[1] = mats[0].specular[2] = 0.5f;
  mats[0].shininess = 100.0f;
  const std::vector<Image> maps;
  auto cpu = make_cpu_backend(static_cast<int>(state.range(1)));
  RasterInputs in{mesh, mats, maps, camera(), kWidth, kHeight};
  in.back_layer = state.range(2) != 0;
  for (auto _ : state) benchmark::DoNotOptimize(cpu->rasterize(in));
  state.counters["triangles"] = static_cast<double>(mesh.triangle_count());
  state.counters["tri/s"] = benchmark::Counter(static_cast<double>(mesh.triangle_count()),
                                               benchmark::Counter::kIsIterationInvariantRate);
}

}  // namespace

// Args: triangle count, CPU threads (0 = all), back layer (1 = also rasterize it).
BENCHMARK_CAPTURE(BM_Rasterize, grid, true)
    ->ArgsProduct({{1000, 100000, 1000000}, {0, 1}, {0}})
    ->ArgsProduct({{1000, 5000, 50000}, {0}, {1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_Rasterize, soup, false)
    ->ArgsProduct({{1000, 100000, 1000000}, {0, 1}, {0}})
    ->ArgsProduct({{1000, 5000, 50000}, {0}, {1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_MAIN();
