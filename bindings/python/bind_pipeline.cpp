// glint_core.pipeline: every stage in one call, each layer returned.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <optional>

#include "bind.h"
#include "convert.h"
#include "glint/backend.h"
#include "glint/memory.h"
#include "glint/mesh.h"
#include "glint/pipeline.h"
#include "glint/validation.h"

using namespace pybind11::literals;

namespace glint::py {
namespace {

pyb::dict py_pipeline(const pyb::handle& position, const pyb::handle& normal,
                      const pyb::handle& specular, const pyb::handle& color,
                      const pyb::handle& projection, float max_distance, float resolution,
                      int steps, float thickness, const std::string& march, int antialias,
                      const std::string& blocked,
                      int blur_size,
                      float blur_separation, const std::string& combine,
                      const std::string& weighting, const std::string& blur,
                      const pyb::handle& specular_base, const pyb::handle& back_position,
                      const pyb::handle& mesh, const std::string& backend, int threads,
                      double memory_limit_mb) {
  PipelineOptions opt;
  opt.weighting = parse_weighting(weighting);
  opt.blur_mode = parse_blur_mode(blur);
  opt.trace = trace_options(max_distance, resolution, steps, thickness, march, antialias, blocked,
                            memory_limit_mb);
  if (auto [w, h] = array_size(position); w > 0) {
    const uint64_t px = uint64_t(w) * uint64_t(h);
    const int copies = back_position.is_none() ? 4 : 5;
    const int outputs = static_cast<int>(pipeline_layer_names().size());
    require_memory(binding_bytes(px, copies, outputs) + pipeline_bytes(w, h, opt, backend != "cpu"),
                   "pipeline at " + std::to_string(w) + "x" + std::to_string(h), memory_limit_mb);
  }
  PipelineInputs in;
  in.position = image_from_array(position, "position", 1.0f, 4);
  in.normal = image_from_array(normal, "normal", 0.0f, 3);
  in.specular = image_from_array(specular, "specular", 0.0f, 4);
  in.color = image_from_array(color, "color", 1.0f, 3);
  in.projection = projection_from_array(projection);
  if (std::optional<Image> back = optional_image(back_position, "back_position", in.position))
    in.back_position = std::move(*back);
  if (!specular_base.is_none()) {
    in.specular_base = image_from_array(specular_base, "specular_base", 0.0f, 3);
    require_same_size(in.position, "position", in.specular_base, "specular_base");
  }
  const std::optional<TriangleMesh> tris = mesh_from_arg(mesh);
  in.mesh = tris ? &*tris : nullptr;
  opt.blur.size = blur_size;
  opt.blur.separation = blur_separation;
  opt.combine = parse_combine(combine);
  opt.threads = threads;
  validate(opt);
  auto be = get_backend(backend, threads);
  PipelineResult res;
  {
    pyb::gil_scoped_release release;
    res = run_pipeline(*be, in, opt);
  }
  pyb::dict out;
  for (const auto& name : pipeline_layer_names()) out[name.c_str()] = array_from_image(std::move(res.layers.at(name)));
  pyb::dict timings;
  pyb::list skipped;
  for (const auto& t : res.timings) {
    timings[t.stage.c_str()] = t.milliseconds;
    if (t.skipped) skipped.append(t.stage);
  }
  out["stats"] = pyb::dict("backend"_a = be->name(), "timings_ms"_a = timings, "skipped"_a = skipped,
                           "reflective_pixels"_a = res.reflective_pixels,
                           "rough_pixels"_a = res.rough_pixels);
  return out;
}

}  // namespace

void bind_pipeline(pyb::module_& m) {
  namespace s = schema;
  const PipelineOptions p;
  m.def("pipeline", &py_pipeline, "position"_a, "normal"_a, "specular"_a, "color"_a, "projection"_a,
        pyb::kw_only(), "max_distance"_a = p.trace.max_distance, "resolution"_a = p.trace.resolution,
        "steps"_a = p.trace.steps, "thickness"_a = p.trace.thickness, "march"_a = s::march.initial_name,
        "antialias"_a = p.trace.antialias, "blocked"_a = to_string(p.trace.blocked), "blur_size"_a = p.blur.size,
        "blur_separation"_a = p.blur.separation, "combine"_a = to_string(p.combine),
        "weighting"_a = to_string(p.weighting), "blur"_a = to_string(p.blur_mode),
        "specular_base"_a = pyb::none(), "back_position"_a = pyb::none(), "mesh"_a = pyb::none(),
        "backend"_a = s::backend.initial_name, "threads"_a = p.threads,
        "memory_limit_mb"_a = p.trace.memory_limit_mb,
        doc_with_options(
            "The whole pipeline. Returns a dict of float32 [H, W, 4] layers named by LAYERS\n"
            "('uv', 'reflection_color', 'reflection_blur', 'specular_weight', 'reflection',\n"
            "'combined') and 'stats': backend used, per-stage timings_ms, skipped stages, pixel\n"
            "counts. specular_base: the engine's own specular (rgb), replaced where a hit is found\n"
            "(combine 'over' only). back_position, mesh: as for trace().",
            {&s::max_distance, &s::resolution, &s::steps, &s::thickness, &s::march, &s::antialias, &s::blocked,
             &s::weighting,
             &s::blur, &s::blur_size, &s::blur_separation, &s::combine, &s::backend, &s::threads,
             &s::memory_limit_mb}));
}

}  // namespace glint::py
