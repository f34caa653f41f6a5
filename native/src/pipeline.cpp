// run_pipeline: the stages in order, skipping what the scene does not need.
#include "glint/pipeline.h"

#include <algorithm>
#include <chrono>
#include <mutex>

#include "parallel.h"
#include "glint/composite.h"
#include "glint/errors.h"
#include "glint/material.h"
#include "glint/memory.h"

namespace glint {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// What the scene needs: how many seen pixels reflect, how many of those are
// rough, and the bounding box of the rough ones (the only place a blur is read).
// Rough is what the blur reads: the box blur mixes by roughness_of(), the cone
// by the lobe's width, which also covers the gloss range (is_glossy()).
struct SceneNeeds {
  size_t reflective = 0;
  size_t rough = 0;
  int box[4] = {0, 0, 0, 0};  // x0, y0, x1, y1 (half-open) of rough reflective pixels
};

SceneNeeds survey(const PipelineInputs& in, bool cone, int threads) {
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
      if (cone ? is_glossy(s) : roughness_of(s) > 0.0f) {
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
                                                 "specular_weight", "reflection", "combined"};
  return names;
}

const std::vector<std::string>& pipeline_stage_names() {
  static const std::vector<std::string> names = {"survey",    "trace",     "reflection_color",
                                                 "specular_weight", "cone_blur", "box_blur",
                                                 "reflection", "combine"};
  return names;
}

PipelineResult run_pipeline(Backend& backend, const PipelineInputs& in, const PipelineOptions& opt) {
  require_image(in.position, "position");
  require_same_size(in.position, "position", in.normal, "normal");
  require_same_size(in.position, "position", in.specular, "specular");
  require_same_size(in.position, "position", in.color, "color");
  const Image* specular_base = in.specular_base.empty() ? nullptr : &in.specular_base;
  if (specular_base) {
    require_same_size(in.position, "position", in.specular_base, "specular_base");
    if (opt.combine != Combine::Over)
      throw InvalidArgument("specular_base", "is replaced only with combine=\"over\"");
  }
  validate_projection(in.projection);
  validate(opt);
  require_memory(pipeline_bytes(in.position.width, in.position.height, opt, backend.name() == "gl"),
                 "pipeline at " + std::to_string(in.position.width) + "x" +
                     std::to_string(in.position.height),
                 opt.trace.memory_limit_mb);

  PipelineResult res;
  const int w = in.position.width, h = in.position.height;
  const char* blur_stage = opt.blur_mode == BlurMode::Cone ? "cone_blur" : "box_blur";
  auto t0 = Clock::now();
  const SceneNeeds needs = survey(in, opt.blur_mode == BlurMode::Cone, opt.threads);
  res.timings.push_back({"survey", ms_since(t0), false});
  res.reflective_pixels = needs.reflective;
  res.rough_pixels = needs.rough;

  if (needs.reflective == 0) {
    // Nothing on screen reflects: the base comes back unchanged and no
    // stage runs (the layers are zero so a debug view still has them).
    for (const char* stage : {"trace", "reflection_color", "specular_weight", blur_stage, "reflection", "combine"})
      res.timings.push_back({stage, 0.0, true});
    for (const auto& name : pipeline_layer_names()) res.layers[name] = Image(w, h);
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
  // Glint's look reads the colour inside the objects' outlines
  // (read_inside_outlines()); the seed's reads at the uv, as the book does.
  // The cone's footprint and the uv layer keep the trace's own uv.
  const Image* read_at = &uv;
  Image moved;
  if (opt.weighting == Weighting::Physical) {
    moved = uv;
    read_inside_outlines(moved, in.position, tin.back_position, opt.trace.thickness, opt.threads);
    read_at = &moved;
  }
  Image color = backend.reflection_color(*read_at, in.color);
  res.timings.push_back({"reflection_color", ms_since(t0), false});

  Image weight;
  if (opt.weighting == Weighting::Physical) {
    t0 = Clock::now();
    weight = backend.specular_weight(in.position, in.normal, in.specular, in.projection);
    res.timings.push_back({"specular_weight", ms_since(t0), false});
  } else {
    weight = Image(w, h);  // the seed's amount is applied inside the reflection stage
    res.timings.push_back({"specular_weight", 0.0, true});
  }

  // The blurred colour; with the cone it already holds the roughness, with the
  // box the reflection stage mixes it in by roughness.
  Image blurred;
  const bool box = opt.blur_mode == BlurMode::Box;
  if (needs.rough == 0 || (box && opt.blur.size == 0)) {
    blurred = color;  // read nowhere: roughness is zero wherever it would be
    res.timings.push_back({blur_stage, 0.0, true});
  } else {
    t0 = Clock::now();
    const MirrorScale mirror = mirror_scale(in.position, in.projection);
    blurred = box ? backend.box_blur(color, opt.blur, needs.box) : backend.cone_blur(color, uv, in.specular, &mirror);
    res.timings.push_back({blur_stage, ms_since(t0), false});
  }

  t0 = Clock::now();
  const Image* weight_in = opt.weighting == Weighting::Physical ? &weight : nullptr;
  Image reflection = box ? backend.reflection(color, &blurred, in.specular, weight_in)
                         : backend.reflection(blurred, nullptr, in.specular, weight_in);
  res.timings.push_back({"reflection", ms_since(t0), false});

  t0 = Clock::now();
  // The share of the lobe the trace found is the blurred colour's alpha for
  // the cone, and the roughness mix of both alphas for the box; the combine
  // reads it from the alpha of `coverage`.
  Image coverage;
  if (specular_base) {
    if (box) {
      coverage = Image(w, h);
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          const float r = roughness_of(in.specular.px(x, y));
          coverage.px(x, y)[3] = color.px(x, y)[3] * (1.0f - r) + blurred.px(x, y)[3] * r;
        }
    } else {
      coverage = blurred;
    }
  }
  Image combined = backend.combine(in.color, reflection, opt.combine, specular_base,
                                   specular_base ? &coverage : nullptr);
  res.timings.push_back({"combine", ms_since(t0), false});

  res.layers["uv"] = std::move(uv);
  res.layers["reflection_color"] = std::move(color);
  res.layers["reflection_blur"] = std::move(blurred);
  res.layers["specular_weight"] = std::move(weight);
  res.layers["reflection"] = std::move(reflection);
  res.layers["combined"] = std::move(combined);
  return res;
}

}  // namespace glint
