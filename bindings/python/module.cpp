// glint_core: the Python face of the Glint core. Arrays in, arrays out; the
// GIL is released while a stage runs so Blender's UI and other threads go on.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <optional>

#include "convert.h"
#include "glint/backend.h"
#include "glint/brdf.h"
#include "glint/composite.h"
#include "glint/errors.h"
#include "glint/marches.h"
#include "glint/memory.h"
#include "glint/mesh.h"
#include "glint/pipeline.h"
#include "glint/presets.h"

namespace pyb = pybind11;
using namespace pybind11::literals;

namespace glint::py {

void bind_exr(pyb::module_& m);
void bind_raster(pyb::module_& m);
void bind_metrics(pyb::module_& m);
void bind_memory(pyb::module_& m);

namespace {

TraceOptions trace_options(float max_distance, float resolution, int steps, float thickness,
                           const std::string& march, const std::string& blocked, double memory_limit_mb) {
  TraceOptions o;
  o.memory_limit_mb = memory_limit_mb;
  o.max_distance = max_distance;
  o.resolution = resolution;
  o.steps = steps;
  o.thickness = thickness;
  o.march = parse_march(march);
  o.blocked = parse_blocked(blocked);
  validate(o);
  return o;
}

// Error messages may quote bytes of a file that are not UTF-8 (lenient_str).
void set_python_error(PyObject* type, const char* what) { PyErr_SetObject(type, lenient_str(what).ptr()); }

// An optional image argument: None, or an array of the position buffer's size.
std::optional<Image> optional_image(const pyb::handle& obj, const char* name, const Image& like) {
  if (obj.is_none()) return std::nullopt;
  Image img = image_from_array(obj, name, 1.0f, 4);
  require_same_size(like, "position", img, name);
  return img;
}

// One trace request's arguments, converted and checked: what trace() and
// composite_layers() share.
struct TraceCall {
  Image pos, nrm;
  Mat4 proj;
  TraceOptions opt;
  std::optional<Image> back, spec;
  std::optional<TriangleMesh> tris;
  std::shared_ptr<Backend> be;
  TraceInputs inputs() const {
    TraceInputs in{pos, nrm, spec ? &*spec : nullptr, proj};
    in.back_position = back ? &*back : nullptr;
    in.mesh = tris ? &*tris : nullptr;
    return in;
  }
};

TraceCall trace_call(const char* what, const pyb::handle& position, const pyb::handle& normal,
                     const pyb::handle& projection, float max_distance, float resolution, int steps,
                     float thickness, const std::string& march, const std::string& blocked,
                     const pyb::handle& back_position, const pyb::handle& mesh, const pyb::handle& specular,
                     const std::string& backend, int threads, double memory_limit_mb, int outputs) {
  // Before any copy: a 32768x32768 request must be refused with the memory still free.
  if (auto [w, h] = array_size(position); w > 0) {
    const uint64_t px = uint64_t(w) * uint64_t(h);
    const int copies = 2 + (back_position.is_none() ? 0 : 1) + (specular.is_none() ? 0 : 1);
    require_memory(binding_bytes(px, copies, outputs) +
                       trace_bytes(w, h, march_info(march).id, backend != "cpu"),
                   std::string(what) + " at " + std::to_string(w) + "x" + std::to_string(h), memory_limit_mb);
  }
  TraceCall c;
  c.pos = image_from_array(position, "position", 1.0f, 4);
  c.nrm = image_from_array(normal, "normal", 0.0f, 3);
  require_same_size(c.pos, "position", c.nrm, "normal");
  c.proj = projection_from_array(projection);
  c.opt = trace_options(max_distance, resolution, steps, thickness, march, blocked, memory_limit_mb);
  c.back = optional_image(back_position, "back_position", c.pos);
  c.spec = optional_image(specular, "specular", c.pos);
  c.tris = mesh_from_arg(mesh);
  c.be = get_backend(backend, threads);
  return c;
}

pyb::array_t<float> py_trace(const pyb::handle& position, const pyb::handle& normal,
                             const pyb::handle& projection, float max_distance, float resolution,
                             int steps, float thickness, const std::string& march,
                             const std::string& blocked, const pyb::handle& back_position,
                             const pyb::handle& mesh, const pyb::handle& specular, const std::string& backend,
                             int threads, double memory_limit_mb) {
  const TraceCall c = trace_call("trace", position, normal, projection, max_distance, resolution, steps,
                                 thickness, march, blocked, back_position, mesh, specular, backend, threads,
                                 memory_limit_mb, 1);
  Image uv;
  {
    pyb::gil_scoped_release release;
    uv = c.be->trace(c.inputs(), c.opt);
  }
  return array_from_image(std::move(uv));
}

pyb::dict py_composite_layers(const pyb::handle& position, const pyb::handle& normal,
                              const pyb::handle& specular, const pyb::handle& projection, float max_distance,
                              float resolution, int steps, float thickness, const std::string& march,
                              const std::string& blocked, const pyb::handle& back_position,
                              const pyb::handle& mesh, const std::string& backend, int threads,
                              double memory_limit_mb) {
  if (specular.is_none()) throw InvalidArgument("specular", "expected a float32 [H, W, 4] array, got None");
  const TraceCall c = trace_call("composite_layers", position, normal, projection, max_distance, resolution,
                                 steps, thickness, march, blocked, back_position, mesh, specular, backend,
                                 threads, memory_limit_mb, 2);
  CompositeLayers layers;
  {
    pyb::gil_scoped_release release;
    layers = composite_layers(*c.be, c.inputs(), c.opt, threads);
  }
  pyb::dict out;
  out["uv"] = array_from_image(std::move(layers.uv));
  out["weight"] = array_from_image(std::move(layers.weight));
  out["reflective_pixels"] = layers.reflective_pixels;
  out["any_rough"] = layers.any_rough;
  return out;
}

pyb::dict py_marches() {
  pyb::dict out;
  for (const MarchInfo& m : march_table()) out[m.name] = m.description;
  return out;
}

pyb::dict py_march_details() {
  pyb::dict out;
  for (const MarchInfo& m : march_table()) {
    pyb::dict knobs;
    for (const MarchKnob& k : m.knobs) knobs[k.option] = k.meaning;
    out[m.name] = pyb::dict("description"_a = m.description, "options"_a = knobs,
                            "needs_mesh"_a = m.needs_mesh,
                            "uses_back_position"_a = m.uses_back_position,
                            "gl"_a = m.gl_program != nullptr);
  }
  return out;
}

pyb::dict trace_kwargs(const TraceOptions& o) {
  return pyb::dict("max_distance"_a = o.max_distance, "resolution"_a = o.resolution,
                   "steps"_a = o.steps, "thickness"_a = o.thickness,
                   "march"_a = march_info(o.march).name);
}

pyb::dict py_presets() {
  pyb::dict out;
  for (const Preset& p : presets()) out[p.name] = trace_kwargs(p.trace);
  return out;
}

pyb::dict py_preset_descriptions() {
  pyb::dict out;
  for (const Preset& p : presets()) out[p.name] = p.description;
  return out;
}

pyb::dict py_pipeline(const pyb::handle& position, const pyb::handle& normal,
                      const pyb::handle& specular, const pyb::handle& color,
                      const pyb::handle& projection, float max_distance, float resolution,
                      int steps, float thickness, const std::string& march, const std::string& blocked,
                      int blur_size,
                      float blur_separation, const std::string& combine,
                      const std::string& weighting, const std::string& blur,
                      const pyb::handle& specular_base, const pyb::handle& back_position,
                      const pyb::handle& mesh, const std::string& backend, int threads,
                      double memory_limit_mb) {
  PipelineOptions opt;
  opt.weighting = parse_weighting(weighting);
  opt.blur_mode = parse_blur_mode(blur);
  opt.trace = trace_options(max_distance, resolution, steps, thickness, march, blocked, memory_limit_mb);
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
}  // namespace glint::py

PYBIND11_MODULE(glint_core, m) {
  using namespace glint;
  using namespace glint::py;
  m.doc() =
      "Glint: screen-space reflections (the seed chapter's pipeline) on numpy arrays.\n"
      "Images are float32 [H, W, C], row 0 at the bottom; view space is Blender's camera space.";

  static pyb::exception<BackendUnavailable> backend_unavailable(m, "BackendUnavailable",
                                                                PyExc_RuntimeError);
  // A MemoryError: code that already handles running out of memory handles a
  // refusal too, and the message says how to raise the limit.
  static pyb::exception<MemoryLimitExceeded> memory_limit_exceeded(m, "MemoryLimitExceeded",
                                                                   PyExc_MemoryError);
  pyb::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InvalidArgument& e) {
      set_python_error(PyExc_ValueError, e.what());
    } catch (const BackendUnavailable& e) {
      set_python_error(backend_unavailable.ptr(), e.what());
    } catch (const MemoryLimitExceeded& e) {
      // Sizes as attributes, so a caller can work out how far to scale down.
      pyb::object exc = pyb::handle(memory_limit_exceeded.ptr())(lenient_str(e.what()));
      exc.attr("needed_bytes") = e.needed_bytes();
      exc.attr("limit_bytes") = e.limit_bytes();
      PyErr_SetObject(memory_limit_exceeded.ptr(), exc.ptr());
    } catch (const pyb::builtin_exception&) {
      throw;  // pybind11's own: its translator knows them
    } catch (const std::runtime_error& e) {
      set_python_error(PyExc_RuntimeError, e.what());
    }
  });

  m.attr("__version__") = "0.1.0";
  m.attr("LAYERS") = pyb::cast(pipeline_layer_names());
  m.attr("STAGES") = pyb::cast(pipeline_stage_names());
  m.attr("MAX_SHININESS") = kMaxShininess;
  m.attr("MAX_STEPS") = kMaxSteps;
  m.def("trace", &py_trace, "position"_a, "normal"_a, "projection"_a, pyb::kw_only(),
        "max_distance"_a = 15.0f, "resolution"_a = 0.3f, "steps"_a = 10, "thickness"_a = 0.5f,
        "march"_a = "seed", "blocked"_a = to_string(TraceOptions{}.blocked), "back_position"_a = pyb::none(),
        "mesh"_a = pyb::none(), "specular"_a = pyb::none(), "backend"_a = "cpu", "threads"_a = 0,
        "memory_limit_mb"_a = 0.0,
        "Reflected-UV buffer (u, v, visibility, visibility) as float32 [H, W, 4].\n"
        "max_distance and thickness are view-space units; resolution in [0, 1];\n"
        "march: a name from marches(). back_position: optional float32 [H, W, 4], the\n"
        "surface behind each pixel (w = 0 where none), read by marches that use true\n"
        "thickness. mesh: (vertices float32 [N, 3], triangles int32 [M, 3]) in the same\n"
        "view space, for marches that trace the scene's triangles ('exact').\n"
        "specular: optional float32 [H, W, 4], the specular buffer: pixels that do not reflect\n"
        "(mean rgb 0) are not traced and report 0, as pipeline() does; their normals still\n"
        "serve the rays that hit them.\n"
        "blocked: 'miss' (default) or 'occluder': what a hiz ray blocked by a surface it passes\n"
        "behind reports; 'occluder' gives (u, v, weight, 0) at what hides the hit (docs/marches.md).\n"
        "memory_limit_mb: MiB the call may allocate (0: GLINT_MEMORY_LIMIT_MB or half of\n"
        "physical memory); a larger request raises MemoryLimitExceeded (a MemoryError).");
  m.def("composite_layers", &py_composite_layers, "position"_a, "normal"_a, "specular"_a, "projection"_a,
        pyb::kw_only(), "max_distance"_a = 15.0f, "resolution"_a = 0.3f, "steps"_a = 10, "thickness"_a = 0.5f,
        "march"_a = "seed", "blocked"_a = to_string(TraceOptions{}.blocked), "back_position"_a = pyb::none(),
        "mesh"_a = pyb::none(), "backend"_a = "cpu", "threads"_a = 0, "memory_limit_mb"_a = 0.0,
        "What a compositor that samples the reflection colour itself needs per frame, in one call\n"
        "(the G-buffer is converted once): {'uv': float32 [H, W, 4] (u, v, vis, 1) from trace(), the uv\n"
        "of misses within 2 pixels of a hit continued from the hits; 'weight': float32 [H, W, 4], rgb\n"
        "specular_weight(), a cone_lod(); 'reflective_pixels': pixels traced; 'any_rough': some lod > 0}.\n"
        "Trace keywords as trace(); nothing is traced when no pixel reflects.");
  m.def(
      "continue_missing_uv",
      [](const pyb::handle& uv, int rings) {
        if (rings < 0) throw InvalidArgument("rings", "expected 0 or more, got " + std::to_string(rings));
        Image u = image_from_array(uv, "uv", 0.0f, 4);
        {
          pyb::gil_scoped_release release;
          continue_missing_uv(u, rings);
        }
        return array_from_image(std::move(u));
      },
      "uv"_a, "rings"_a = 2,
      "A copy of uv (u, v, vis, _) where `rings` rings of misses (vis <= 0) around the hits take\n"
      "the mean uv of their hit (or earlier-ring) 3x3 neighbours; vis and the 4th channel unchanged.\n"
      "What composite_layers() does to its uv image.");
  m.def("marches", &py_marches, "{name: one-line description} of every march trace() accepts.");
  m.def("march_details", &py_march_details,
        "{name: {description, options: {keyword: meaning}, needs_mesh, uses_back_position, gl}}.");
  m.def("presets", &py_presets, "{name: trace() keyword arguments} of every preset.");
  m.def("preset_descriptions", &py_preset_descriptions, "{name: one line on what it measured}.");

  m.def("pipeline", &py_pipeline, "position"_a, "normal"_a, "specular"_a, "color"_a, "projection"_a,
        pyb::kw_only(), "max_distance"_a = 15.0f, "resolution"_a = 0.3f, "steps"_a = 10,
        "thickness"_a = 0.5f, "march"_a = "seed", "blocked"_a = to_string(TraceOptions{}.blocked),
        "blur_size"_a = 8, "blur_separation"_a = 1.0f,
        "combine"_a = "over", "weighting"_a = to_string(PipelineOptions{}.weighting),
        "blur"_a = to_string(PipelineOptions{}.blur_mode), "specular_base"_a = pyb::none(),
        "back_position"_a = pyb::none(), "mesh"_a = pyb::none(),
        "backend"_a = "cpu", "threads"_a = 0, "memory_limit_mb"_a = 0.0,
        "The whole pipeline. Returns a dict of float32 [H, W, 4] layers named by LAYERS\n"
        "('uv', 'reflection_color', 'reflection_blur', 'specular_weight', 'reflection',\n"
        "'combined') and 'stats': backend used, per-stage timings_ms, skipped stages, pixel\n"
        "counts. weighting: 'physical' (F0 * A + B, split-sum) or 'seed' (mean F0); blur:\n"
        "'cone' (ray length x GGX cone, mip chain) or 'box' (blur_size, blur_separation);\n"
        "specular_base: the engine's own specular (rgb), replaced where a hit is found\n"
        "(combine 'over' only). memory_limit_mb: as for trace().");

  m.def(
      "reflection_color",
      [](const pyb::handle& uv, const pyb::handle& color, const std::string& backend) {
        Image u = image_from_array(uv, "uv", 0.0f, 4), c = image_from_array(color, "color", 1.0f, 3);
        auto be = get_backend(backend);
        pyb::gil_scoped_release release;
        Image r = be->reflection_color(u, c);
        pyb::gil_scoped_acquire acquire;
        return array_from_image(std::move(r));
      },
      "uv"_a, "color"_a, pyb::kw_only(), "backend"_a = "cpu",
      "Colour at the reflected uv (bilinear, clamp to edge), premultiplied by visibility.");

  m.def(
      "box_blur",
      [](const pyb::handle& image, int size, float separation, const std::string& backend) {
        Image src = image_from_array(image, "image", 1.0f, 3);
        BlurOptions o;
        o.size = size;
        o.separation = separation;
        try {
          validate(o);
        } catch (const InvalidArgument& e) {
          // The options struct names its fields as pipeline() spells them;
          // this function's keywords are `size` and `separation`.
          const std::string kw = e.argument() == "blur_size" ? "size" : "separation";
          const std::string msg = e.what();
          throw InvalidArgument(kw, msg.substr(msg.find(": ") + 2));
        }
        auto be = get_backend(backend);
        pyb::gil_scoped_release release;
        Image r = be->box_blur(src, o, nullptr);
        pyb::gil_scoped_acquire acquire;
        return array_from_image(std::move(r));
      },
      "image"_a, pyb::kw_only(), "size"_a = 8, "separation"_a = 1.0f, "backend"_a = "cpu",
      "(2 * size + 1)^2 box average of all four channels, taps `separation` pixels apart.");

  m.def(
      "specular_weight",
      [](const pyb::handle& position, const pyb::handle& normal, const pyb::handle& specular,
         const pyb::handle& projection, const std::string& backend) {
        const Image pos = image_from_array(position, "position", 1.0f, 4);
        const Image nrm = image_from_array(normal, "normal", 0.0f, 3);
        const Image spec = image_from_array(specular, "specular", 0.0f, 4);
        const Mat4 proj = projection_from_array(projection);
        auto be = get_backend(backend);
        pyb::gil_scoped_release release;
        Image r = be->specular_weight(pos, nrm, spec, proj);
        pyb::gil_scoped_acquire acquire;
        return array_from_image(std::move(r));
      },
      "position"_a, "normal"_a, "specular"_a, "projection"_a, pyb::kw_only(), "backend"_a = "cpu",
      "Physical reflection weight: rgb = F0 * A + B (split-sum table at N.V and roughness),\n"
      "a = mean of the rgb; 0 where a pixel is unseen or does not reflect.");

  m.def(
      "cone_blur",
      [](const pyb::handle& color, const pyb::handle& uv, const pyb::handle& specular,
         const std::string& backend) {
        Image c = image_from_array(color, "reflection_color", 0.0f, 4);
        Image u = image_from_array(uv, "uv", 0.0f, 4);
        Image s = image_from_array(specular, "specular", 0.0f, 4);
        auto be = get_backend(backend);
        pyb::gil_scoped_release release;
        Image r = be->cone_blur(c, u, s);
        pyb::gil_scoped_acquire acquire;
        return array_from_image(std::move(r));
      },
      "reflection_color"_a, "uv"_a, "specular"_a, pyb::kw_only(), "backend"_a = "cpu",
      "The reflection colour blurred by each pixel's GGX cone: footprint 2 * ray length in\n"
      "pixels * cone tan, read trilinearly from a 2x2 box mip chain.");

  m.def(
      "cone_lod",
      [](const pyb::handle& uv, const pyb::handle& specular) {
        const Image u = image_from_array(uv, "uv", 0.0f, 4);
        const Image s = image_from_array(specular, "specular", 0.0f, 4);
        Image r;
        {
          pyb::gil_scoped_release release;
          r = cone_lod(u, s);
        }
        pyb::array_t<float> out({r.height, r.width});
        float* o = out.mutable_data();
        for (int y = 0; y < r.height; ++y)
          for (int x = 0; x < r.width; ++x) o[static_cast<size_t>(y) * r.width + x] = r.px(x, y)[0];
        return out;
      },
      "uv"_a, "specular"_a,
      "[H, W] level of detail of the cone blur per pixel: log2(2 * ray length in pixels *\n"
      "cone tan), 0 where that footprint is within a pixel, no hit was found or the pixel\n"
      "is a mirror or does not reflect (the rule cone_blur applies).");

  m.def(
      "reflection",
      [](const pyb::handle& color, const pyb::handle& blurred, const pyb::handle& specular,
         const pyb::handle& weight, const std::string& backend) {
        Image c = image_from_array(color, "reflection_color", 0.0f, 4);
        std::optional<Image> b, w;
        if (!blurred.is_none()) b = image_from_array(blurred, "reflection_blur", 0.0f, 4);
        Image s = image_from_array(specular, "specular", 0.0f, 4);
        if (!weight.is_none()) w = image_from_array(weight, "weight", 0.0f, 4);
        auto be = get_backend(backend);
        pyb::gil_scoped_release release;
        Image r = be->reflection(c, b ? &*b : nullptr, s, w ? &*w : nullptr);
        pyb::gil_scoped_acquire acquire;
        return array_from_image(std::move(r));
      },
      "reflection_color"_a, "reflection_blur"_a, "specular"_a, pyb::kw_only(),
      "weight"_a = pyb::none(), "backend"_a = "cpu",
      "mix(colour, blurred, roughness) (the colour alone when reflection_blur is None) times\n"
      "weight (rgb on colour, a on alpha) or, without one, the specular amount.");

  m.def(
      "combine",
      [](const pyb::handle& base, const pyb::handle& reflection, const std::string& mode,
         const pyb::handle& specular_base, const pyb::handle& coverage, const std::string& backend) {
        Image b = image_from_array(base, "color", 1.0f, 3);
        Image r = image_from_array(reflection, "reflection", 0.0f, 4);
        const Combine c = parse_combine(mode);
        std::optional<Image> sb, cov;
        if (!specular_base.is_none()) sb = image_from_array(specular_base, "specular_base", 0.0f, 3);
        if (!coverage.is_none()) cov = image_from_array(coverage, "coverage", 0.0f, 4);
        auto be = get_backend(backend);
        pyb::gil_scoped_release release;
        Image out = be->combine(b, r, c, sb ? &*sb : nullptr, cov ? &*cov : nullptr);
        pyb::gil_scoped_acquire acquire;
        return array_from_image(std::move(out));
      },
      "color"_a, "reflection"_a, pyb::kw_only(), "mode"_a = "over", "specular_base"_a = pyb::none(),
      "coverage"_a = pyb::none(), "backend"_a = "cpu",
      "'over': base * (1 - a) + reflection.rgb (visibility once); 'seed': the demo's mix.\n"
      "With specular_base (and coverage, whose alpha is the share the trace found):\n"
      "max(base - specular_base * coverage.a, 0) + reflection.rgb.");

  m.def("shininess_to_alpha", &shininess_to_alpha, "shininess"_a,
        "clamp(shininess / 127.75, 0, 1): the specular buffer's alpha.");
  m.def("shininess_from_hardness", &shininess_from_hardness, "hardness"_a,
        "Blender Internal hardness (1..511) to shininess: hardness / 4 (511 -> 127.75).");
  m.def(
      "env_brdf",
      [](float n_dot_v, float alpha) {
        float a, b;
        env_brdf(n_dot_v, alpha, &a, &b);
        return pyb::make_tuple(a, b);
      },
      "n_dot_v"_a, "alpha"_a,
      "(A, B) of the split-sum table at N.V and GGX alpha (bilinear between its nodes).");
  m.def("ggx_alpha", [](float shininess_alpha) {
        const float s[4] = {1.0f, 1.0f, 1.0f, shininess_alpha};
        return ggx_alpha_of(s);
      }, "shininess_alpha"_a,
      "GGX alpha of a specular-buffer alpha: sqrt(2 / (511 a + 2)), 0 at a >= 1 (a mirror).");
  m.def("cone_tan", &cone_tan, "alpha"_a,
        "tan of the reflection cone's half-angle for GGX alpha: 2 a / (1 - a^2), capped.");
  m.attr("WEIGHTINGS") = pyb::make_tuple(to_string(Weighting::Physical), to_string(Weighting::Seed));
  m.attr("BLURS") = pyb::make_tuple(to_string(BlurMode::Cone), to_string(BlurMode::Box));
  m.def("gl_compiled_in", &gl_compiled_in, "True when this build has the OpenGL backend.");
  m.def(
      "backend_name",
      [](const std::string& backend) { return get_backend(backend)->name(); }, "backend"_a = "auto",
      "The backend a name resolves to ('auto' -> 'gl' or 'cpu'); raises BackendUnavailable.");

  bind_exr(m);
  bind_raster(m);
  bind_metrics(m);
  bind_memory(m);
  bind_exact(m);
}
