// run_pipeline: the stages in order, skipping what the scene does not need.
#include "glint/pipeline.h"

#include <algorithm>
#include <chrono>
#include <mutex>

#include "parallel.h"
#include "glint/errors.h"
#include "glint/memory.h"

namespace glint {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// What the scene needs: how many seen pixels reflect, how many of those are
// rough, and the bounding box of the rough ones (the only place a blur is read).
struct SceneNeeds {
  size_t reflective = 0;
  size_t rough = 0;
  int box[4] = {0, 0, 0, 0};  // x0, y0, x1, y1 (half-open) of rough reflective pixels
};

SceneNeeds survey(const PipelineInputs& in, int threads) {
  SceneNeeds needs;
  std::mutex mu;
  int bx0 = in.specular.width, by0 = in.specular.height, bx1 = 0, by1 = 0;
  parallel_rows(0, in.specular.height, threads, [&](int y) {
    size_t refl = 0, rough = 0;
    int rx0 = in.specular.width, rx1 = -1;
    for (int x = 0; x < in.specular.width; ++x) {
      const float* s = in.specular.px(x, y);
      if (!is_reflective(s) || !texel_seen(in.position.px(x, y))) continue;
      ++refl;
      if (roughness_of(s) > 0.0f) {
        ++rough;
        rx0 = std::min(rx0, x);
        rx1 = std::max(rx1, x);
      }
    }
    if (refl == 0) return;
    std::lock_guard<std::mutex> lock(mu);
    needs.reflective += refl;
    needs.rough += rough;
    if (rough) {
      bx0 = std::min(bx0, rx0);
      bx1 = std::max(bx1, rx1 + 1);
      by0 = std::min(by0, y);
      by1 = std::max(by1, y + 1);
    }
  });
  if (needs.rough) {
    needs.box[0] = bx0;
    needs.box[1] = by0;
    needs.box[2] = bx1;
    needs.box[3] = by1;
  }
  return needs;
}

}  // namespace

const std::vector<std::string>& pipeline_layer_names() {
  static const std::vector<std::string> names = {"uv", "reflection_color", "reflection_blur",
                                                 "reflection", "combined"};
  return names;
}

PipelineResult run_pipeline(Backend& backend, const PipelineInputs& in, const PipelineOptions& opt) {
  require_image(in.position, "position");
  require_same_size(in.position, "position", in.normal, "normal");
  require_same_size(in.position, "position", in.specular, "specular");
  require_same_size(in.position, "position", in.color, "color");
  validate_projection(in.projection);
  validate(opt);
  require_memory(pipeline_bytes(in.position.width, in.position.height, opt, backend.name() == "gl"),
                 "pipeline at " + std::to_string(in.position.width) + "x" +
                     std::to_string(in.position.height),
                 opt.trace.memory_limit_mb);

  PipelineResult res;
  const int w = in.position.width, h = in.position.height;
  auto t0 = Clock::now();
  const SceneNeeds needs = survey(in, opt.threads);
  res.timings.push_back({"survey", ms_since(t0), false});
  res.reflective_pixels = needs.reflective;
  res.rough_pixels = needs.rough;

  if (needs.reflective == 0) {
    // Nothing on screen reflects: the base comes back unchanged and no
    // stage runs (the layers are zero so a debug view still has them).
    for (const char* stage : {"trace", "reflection_color", "box_blur", "reflection", "combine"})
      res.timings.push_back({stage, 0.0, true});
    res.layers["uv"] = Image(w, h);
    res.layers["reflection_color"] = Image(w, h);
    res.layers["reflection_blur"] = Image(w, h);
    res.layers["reflection"] = Image(w, h);
    res.layers["combined"] = in.color;
    return res;
  }

  t0 = Clock::now();
  TraceInputs tin{in.position, in.normal, &in.specular, in.projection};
  tin.back_position = in.back_position.empty() ? nullptr : &in.back_position;
  tin.mesh = in.mesh;
  Image uv = backend.trace(tin, opt.trace);
  res.timings.push_back({"trace", ms_since(t0), false});

  t0 = Clock::now();
  Image color = backend.reflection_color(uv, in.color);
  res.timings.push_back({"reflection_color", ms_since(t0), false});

  Image blurred;
  if (needs.rough == 0 || opt.blur.size == 0) {
    blurred = color;  // read nowhere: roughness is zero wherever it would be
    res.timings.push_back({"box_blur", 0.0, true});
  } else {
    t0 = Clock::now();
    blurred = backend.box_blur(color, opt.blur, needs.box);
    res.timings.push_back({"box_blur", ms_since(t0), false});
  }

  t0 = Clock::now();
  Image reflection = backend.reflection(color, blurred, in.specular);
  res.timings.push_back({"reflection", ms_since(t0), false});

  t0 = Clock::now();
  Image combined = backend.combine(in.color, reflection, opt.combine);
  res.timings.push_back({"combine", ms_since(t0), false});

  res.layers["uv"] = std::move(uv);
  res.layers["reflection_color"] = std::move(color);
  res.layers["reflection_blur"] = std::move(blurred);
  res.layers["reflection"] = std::move(reflection);
  res.layers["combined"] = std::move(combined);
  return res;
}

}  // namespace glint
