// libFuzzer harness: the CPU rasterizer on arbitrary triangles. The bytes
// choose the size (1x1 up to 48x48), a few materials, the projection, and up
// to 64 triangles whose corners and normals are raw float bits (NaN, Inf,
// denormals, huge, behind the eye, edge-on). glint::Error is an answer;
// a crash or a sanitizer report is a finding. Covered pixels must hold
// w = 1 and a unit normal.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <vector>

#include "fuzz_input.h"
#include "glint/errors.h"
#include "glint/raster.h"
#include "glint/stages.h"

using glint::fuzz::Bytes;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::unique_ptr<glint::Backend> cpu = glint::make_cpu_backend(1);
  Bytes in(data, size);
  const int w = in.in_range(1, 48), h = in.in_range(1, 48);
  const bool back_layer = in.in_range(0, 1) == 1;
  glint::Mat4 proj;
  if (in.in_range(0, 3) == 0) {
    for (double& v : proj.m) v = in.any_float();
  } else {
    proj = glint::perspective(0.2 + in.in_range(0, 100) * 0.025, double(w) / h,
                              0.01 + in.in_range(0, 100) * 0.01, 10.0 + in.in_range(0, 1000));
  }
  std::vector<glint::Material> materials(static_cast<size_t>(in.in_range(1, 4)));
  for (auto& m : materials) {
    m.specular[0] = in.in_range(0, 100) / 100.0f;
    m.shininess = in.in_range(0, 511) / 4.0f;
  }
  // Small coordinates mostly, so that triangles land on screen; raw bits sometimes.
  auto coord = [&]() {
    const int mode = in.in_range(0, 7);
    return mode == 0 ? in.any_float() : (in.take<int8_t>() / 16.0f);
  };
  glint::Mesh mesh;
  const int tris = in.in_range(0, 64);
  for (int t = 0; t < tris; ++t) {
    for (int k = 0; k < 9; ++k) mesh.positions.push_back(coord());
    for (int k = 0; k < 9; ++k) mesh.normals.push_back(coord());
    mesh.material.push_back(in.in_range(0, static_cast<int>(materials.size()) - 1));
  }
  const std::vector<glint::Image> maps;
  glint::RasterInputs rin{mesh, materials, maps, proj, w, h};
  rin.back_layer = back_layer;
  try {
    const glint::GBufferImages g = cpu->rasterize(rin);
    for (size_t i = 0; i < g.position.pixel_count(); ++i) {
      const float* p = &g.position.data[i * 4];
      if (p[3] != 0.0f && p[3] != 1.0f) std::abort();
      if (p[3] == 1.0f) {
        const float* n = &g.normal.data[i * 4];
        const double len = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
        if (!(std::fabs(len - 1.0) < 1e-3)) std::abort();
      }
    }
  } catch (const glint::Error&) {
  }
  return 0;
}
