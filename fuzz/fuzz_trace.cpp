// libFuzzer harness: the CPU trace on arbitrary buffers and options. The
// bytes choose the size (1x1 up to 24x24), the march (every row of
// march_table() that does not need the scene's triangles), the options and
// the projection, then fill position, normal, specular and back_position
// with raw float bits: NaN, Inf, denormals, huge and negative values.
// glint::Error (a refused option or projection) is an answer; a crash, a
// hang or a sanitizer report is a finding. The output must stay in range.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <vector>

#include "fuzz_input.h"
#include "glint/errors.h"
#include "glint/marches.h"
#include "glint/projection.h"
#include "glint/stages.h"

using glint::fuzz::Bytes;

namespace {

std::vector<glint::March> traceable_marches() {
  std::vector<glint::March> out;
  for (const glint::MarchInfo& m : glint::march_table())
    if (!m.needs_mesh) out.push_back(m.id);
  return out;
}

glint::Mat4 fuzz_projection(Bytes& in, int w, int h) {
  switch (in.in_range(0, 2)) {
    case 0: return glint::perspective(0.3 + in.in_range(0, 100) * 0.02, double(w) / h, 0.1, 100.0);
    case 1: return glint::orthographic(1.0 + in.in_range(0, 50), 1.0 + in.in_range(0, 50), 0.1, 100.0);
    default: {
      glint::Mat4 p;
      for (double& v : p.m) v = in.any_float();
      return p;
    }
  }
}

void fill(glint::Image& img, Bytes& in) {
  for (float& v : img.data) v = in.left() ? in.any_float() : 0.0f;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::vector<glint::March> marches = traceable_marches();
  static const std::unique_ptr<glint::Backend> cpu = glint::make_cpu_backend(1);
  Bytes in(data, size);
  const int w = in.in_range(1, 24), h = in.in_range(1, 24);
  glint::TraceOptions opt;
  opt.march = marches[static_cast<size_t>(in.in_range(0, static_cast<int>(marches.size()) - 1))];
  opt.max_distance = in.any_float();
  opt.resolution = in.any_float();
  opt.steps = in.in_range(0, 200);
  opt.thickness = in.any_float();
  const int flags = in.in_range(0, 3);
  const glint::Mat4 proj = fuzz_projection(in, w, h);
  glint::Image pos(w, h), nrm(w, h), spec(w, h), back(w, h);
  fill(pos, in);
  fill(nrm, in);
  fill(spec, in);
  fill(back, in);
  glint::TraceInputs tin{pos, nrm, (flags & 1) ? &spec : nullptr, proj};
  tin.back_position = (flags & 2) ? &back : nullptr;
  try {
    const glint::Image uv = cpu->trace(tin, opt);
    if (uv.width != w || uv.height != h) std::abort();
    for (size_t i = 0; i < uv.pixel_count(); ++i) {
      const float vis = uv.data[i * 4 + 2];
      if (!(vis >= 0.0f && vis <= 1.0f)) std::abort();  // visibility is a share
    }
  } catch (const glint::Error&) {
  }
  return 0;
}
