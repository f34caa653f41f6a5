// glint_core.trace and composite_layers (one trace request each), and the
// tables of marches and presets they take their names from.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <optional>

#include "bind.h"
#include "convert.h"
#include "glint/backend.h"
#include "glint/composite.h"
#include "glint/errors.h"
#include "glint/marches.h"
#include "glint/memory.h"
#include "glint/mesh.h"
#include "glint/presets.h"
#include "glint/validation.h"

using namespace pybind11::literals;

namespace glint::py {

TraceOptions trace_options(float max_distance, float resolution, int steps, float thickness,
                           const std::string& march, int antialias, const std::string& blocked,
                           double memory_limit_mb) {
  TraceOptions o;
  o.memory_limit_mb = memory_limit_mb;
  o.max_distance = max_distance;
  o.resolution = resolution;
  o.steps = steps;
  o.thickness = thickness;
  o.march = parse_march(march);
  o.antialias = antialias;
  o.blocked = parse_blocked(blocked);
  validate(o);
  return o;
}

// An optional image argument: None, or an array of the position buffer's size.
std::optional<Image> optional_image(const pyb::handle& obj, const char* name, const Image& like) {
  if (obj.is_none()) return std::nullopt;
  Image img = image_from_array(obj, name, 1.0f, 4);
  require_same_size(like, "position", img, name);
  return img;
}

namespace {

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
                     float thickness, const std::string& march, int antialias, const std::string& blocked,
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
  c.opt = trace_options(max_distance, resolution, steps, thickness, march, antialias, blocked, memory_limit_mb);
  c.back = optional_image(back_position, "back_position", c.pos);
  c.spec = optional_image(specular, "specular", c.pos);
  c.tris = mesh_from_arg(mesh);
  c.be = get_backend(backend, threads);
  return c;
}

pyb::array_t<float> py_trace(const pyb::handle& position, const pyb::handle& normal,
                             const pyb::handle& projection, float max_distance, float resolution,
                             int steps, float thickness, const std::string& march, int antialias,
                             const std::string& blocked, const pyb::handle& back_position,
                             const pyb::handle& mesh, const pyb::handle& specular, const std::string& backend,
                             int threads, double memory_limit_mb) {
  const TraceCall c = trace_call("trace", position, normal, projection, max_distance, resolution, steps,
                                 thickness, march, antialias, blocked, back_position, mesh, specular, backend, threads,
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
                              int antialias, const std::string& blocked, const pyb::handle& back_position,
                              const pyb::handle& mesh, const pyb::handle& back_albedo, bool world_specular,
                              const std::string& backend, int threads, double memory_limit_mb) {
  if (specular.is_none()) throw InvalidArgument("specular", "expected a float32 [H, W, 4] array, got None");
  const TraceCall c = trace_call("composite_layers", position, normal, projection, max_distance, resolution,
                                 steps, thickness, march, antialias, blocked, back_position, mesh, specular, backend,
                                 threads, memory_limit_mb, back_albedo.is_none() ? 2 : 4);
  const std::optional<Image> albedo = optional_image(back_albedo, "back_albedo", c.pos);
  CompositeLayers layers;
  {
    pyb::gil_scoped_release release;
    layers = composite_layers(*c.be, c.inputs(), c.opt, threads, albedo ? &*albedo : nullptr, world_specular);
  }
  pyb::dict out;
  out["uv"] = array_from_image(std::move(layers.uv));
  out["weight"] = array_from_image(std::move(layers.weight));
  if (albedo) {
    out["hidden"] = array_from_image(std::move(layers.hidden));
    out["hidden_pixels"] = layers.hidden_pixels;
  }
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
                   "march"_a = march_info(o.march).name, "antialias"_a = o.antialias);
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

}  // namespace

void bind_trace(pyb::module_& m) {
  namespace s = schema;
  const TraceOptions t;
  m.def("trace", &py_trace, "position"_a, "normal"_a, "projection"_a, pyb::kw_only(),
        "max_distance"_a = t.max_distance, "resolution"_a = t.resolution, "steps"_a = t.steps,
        "thickness"_a = t.thickness, "march"_a = s::march.initial_name, "antialias"_a = t.antialias,
        "blocked"_a = to_string(t.blocked),
        "back_position"_a = pyb::none(), "mesh"_a = pyb::none(), "specular"_a = pyb::none(),
        "backend"_a = s::backend.initial_name, "threads"_a = s::threads.initial_int(),
        "memory_limit_mb"_a = t.memory_limit_mb,
        doc_with_options(
            "Reflected-UV buffer (u, v, visibility, visibility) as float32 [H, W, 4].\n"
            "back_position: optional float32 [H, W, 4], the surface behind each pixel (w = 0 where\n"
            "none), read by marches that use true thickness. mesh: (vertices float32 [N, 3],\n"
            "triangles int32 [M, 3]) in the same view space, for marches that trace the scene's\n"
            "triangles ('exact').\n"
            "specular: optional float32 [H, W, 4], the specular buffer: pixels that do not reflect\n"
            "(mean rgb 0) are not traced and report 0, as pipeline() does; their normals still\n"
            "serve the rays that hit them.\n"
            "blocked='occluder' gives (u, v, weight, 0) at what hides the hit (docs/marches.md).\n"
            "A request over memory_limit_mb raises MemoryLimitExceeded (a MemoryError).",
            {&s::max_distance, &s::resolution, &s::steps, &s::thickness, &s::march, &s::antialias, &s::blocked,
             &s::backend,
             &s::threads, &s::memory_limit_mb}));
  m.def("composite_layers", &py_composite_layers, "position"_a, "normal"_a, "specular"_a, "projection"_a,
        pyb::kw_only(), "max_distance"_a = t.max_distance, "resolution"_a = t.resolution, "steps"_a = t.steps,
        "thickness"_a = t.thickness, "march"_a = s::march.initial_name, "antialias"_a = t.antialias,
        "blocked"_a = to_string(t.blocked),
        "back_position"_a = pyb::none(), "mesh"_a = pyb::none(), "back_albedo"_a = pyb::none(),
        "world_specular"_a = false,
        "backend"_a = s::backend.initial_name, "threads"_a = s::threads.initial_int(),
        "memory_limit_mb"_a = t.memory_limit_mb,
        "What a compositor that samples the reflection colour itself needs per frame, in one call\n"
        "(the G-buffer is converted once): {'uv': float32 [H, W, 4] (u, v, vis, replaced) from trace(), the uv\n"
        "of misses within 2 pixels of a hit continued from the hits; 'weight': float32 [H, W, 4], rgb\n"
        "specular_weight(), a cone_lod() continued to the misses around blurred hits (continue_lod());\n"
        "'reflective_pixels': pixels traced; 'any_rough': some lod > 0}. `replaced`: the share of the\n"
        "engine's specular the pixel's reflection replaces (vis, or the hidden image's vis).\n"
        "back_albedo: optional float32 [H, W, 4], rasterize()'s back_albedo: adds 'hidden' (hidden_sides():\n"
        "(albedo, vis) where a ray met an object's hidden side, whose uv then has vis 0; with the hiz\n"
        "march also the uncertain shares of settle_uncertain_shares(), whose uv keeps its vis) and\n"
        "'hidden_pixels'. world_specular: the engine's specular is W x one colour everywhere (a uniform\n"
        "world); `replaced` then also takes out the part of each hit's own specular that the camera\n"
        "sees and the ray does not (reweight_hit_specular() in glint/composite.h; it may leave [0, 1]).\n"
        "Trace keywords as trace(); nothing is traced when no pixel reflects.");
  m.def(
      "hidden_sides",
      [](const pyb::handle& uv, const pyb::handle& back_albedo) {
        const Image u = image_from_array(uv, "uv", 0.0f, 4);
        const Image a = image_from_array(back_albedo, "back_albedo", 0.0f, 4);
        uint64_t count = 0;
        Image out;
        {
          pyb::gil_scoped_release release;
          out = hidden_sides(u, a, count);
        }
        return pyb::make_tuple(array_from_image(std::move(out)), count);
      },
      "uv"_a, "back_albedo"_a,
      "(hidden, count) from a trace's uv (u, v, vis, hit vis) with blocked='occluder': where the\n"
      "report is an occluder (vis > 0, hit vis 0) whose texel has a back surface (back_albedo alpha\n"
      "> 0), hidden = (back_albedo rgb, vis): the hidden side the ray entered; 0 elsewhere.");
  m.def(
      "settle_uncertain_shares",
      [](const pyb::handle& uv, const pyb::handle& hidden, const pyb::handle& back_albedo) {
        Image u = image_from_array(uv, "uv", 0.0f, 4);
        Image h = image_from_array(hidden, "hidden", 0.0f, 4);
        const Image a = image_from_array(back_albedo, "back_albedo", 0.0f, 4);
        uint64_t count = 0;
        {
          pyb::gil_scoped_release release;
          count = settle_uncertain_shares(u, h, a);
        }
        return pyb::make_tuple(array_from_image(std::move(u)), array_from_image(std::move(h)), count);
      },
      "uv"_a, "hidden"_a, "back_albedo"_a,
      "(uv, hidden, count): a hiz trace's uv (blocked='occluder') and hidden_sides()'s image, with\n"
      "the hits the march was unsure of settled from their neighbours where all eight report\n"
      "something within REUSE_PIXELS of the hit: the rest of the screen-edge fade goes to the\n"
      "hidden side beside it (hidden = (albedo x share / fade, share)) or else to the hit (vis =\n"
      "fade). count: the pixels given a hidden share. docs/hiz.md, *Uncertain shares inside a\n"
      "reflection*.");
  m.def(
      "positive_bin_means",
      [](pyb::array_t<float> values, pyb::array_t<int, pyb::array::c_style | pyb::array::forcecast> row_bins,
         pyb::array_t<int, pyb::array::c_style | pyb::array::forcecast> col_bins, std::pair<int, int> shape,
         int threads) {
        if (values.ndim() != 2)
          throw InvalidArgument("values", "expected a 2-D float32 array, got " + std::to_string(values.ndim()) +
                                              " dimensions");
        const auto rows = values.shape(0), cols = values.shape(1);
        if (row_bins.ndim() != 1 || row_bins.shape(0) != rows)
          throw InvalidArgument("row_bins", "expected one bin per row (" + std::to_string(rows) + ")");
        if (col_bins.ndim() != 1 || col_bins.shape(0) != cols)
          throw InvalidArgument("col_bins", "expected one bin per column (" + std::to_string(cols) + ")");
        const auto [bin_rows, bin_cols] = shape;
        if (bin_rows < 1 || bin_cols < 1 || bin_rows > kMaxImageSide || bin_cols > kMaxImageSide)
          throw InvalidArgument("shape", "expected 1 to " + std::to_string(kMaxImageSide) + " bins each way");
        pyb::array_t<float> out({bin_rows, bin_cols});
        const float* v = values.data();
        const std::ptrdiff_t rs = values.strides(0) / static_cast<std::ptrdiff_t>(sizeof(float));
        const std::ptrdiff_t cs = values.strides(1) / static_cast<std::ptrdiff_t>(sizeof(float));
        if (values.strides(0) % sizeof(float) || values.strides(1) % sizeof(float))
          throw InvalidArgument("values", "expected strides in whole floats");
        float* o = out.mutable_data();
        {
          pyb::gil_scoped_release release;
          positive_bin_means(v, rs, cs, static_cast<int>(rows), static_cast<int>(cols), row_bins.data(),
                             col_bins.data(), bin_rows, bin_cols, o, threads);
        }
        return out;
      },
      "values"_a, "row_bins"_a, "col_bins"_a, "shape"_a, "threads"_a = 0,
      "float32 [shape]: per bin of `values` (2-D float32, any strides: a channel of an image),\n"
      "the mean of its positive values, 0 where it has none; row_bins / col_bins give each\n"
      "row's and column's bin, never decreasing. Sums in numpy add.reduceat's order, so the\n"
      "add-on's coarse blur levels get the bits its numpy rule gives (logic/compositing.py).");
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
  m.def(
      "read_inside_outlines",
      [](const pyb::handle& uv, const pyb::handle& position, const pyb::handle& back_position, float thickness,
         int threads) {
        Image u = image_from_array(uv, "uv", 0.0f, 4);
        const Image p = image_from_array(position, "position", 1.0f, 4);
        Image b;
        if (!back_position.is_none()) b = image_from_array(back_position, "back_position", 0.0f, 4);
        TraceOptions o;  // the thickness's range, as trace() checks it
        o.thickness = thickness;
        validate(o);
        {
          pyb::gil_scoped_release release;
          read_inside_outlines(u, p, back_position.is_none() ? nullptr : &b, thickness, threads);
        }
        return array_from_image(std::move(u));
      },
      "uv"_a, "position"_a, pyb::kw_only(), "back_position"_a = pyb::none(), "thickness"_a = TraceOptions{}.thickness,
      "threads"_a = 0,
      "A copy of uv where each reported uv (vis > 0) in a texel on an object's outline (a 4-neighbour\n"
      "unseen or farther than its depth plus its thickness: back_position's, else `thickness`) moves\n"
      "to the centre of the texel one step inside the object: where Glint's look reads the colour\n"
      "(composite_layers() and pipeline() with weighting='physical' do this; the seed's look does not).");
  m.def(
      "continue_lod",
      [](const pyb::handle& weight, const pyb::handle& uv, const pyb::handle& specular,
         const pyb::handle& position) {
        Image w = image_from_array(weight, "weight", 0.0f, 4);
        const Image u = image_from_array(uv, "uv", 0.0f, 4);
        const Image s = image_from_array(specular, "specular", 0.0f, 4);
        const Image p = image_from_array(position, "position", 1.0f, 4);
        require_same_size(w, "weight", u, "uv");
        require_same_size(w, "weight", s, "specular");
        require_same_size(w, "weight", p, "position");
        {
          pyb::gil_scoped_release release;
          continue_lod_into_misses(w, u, s, p);
        }
        return array_from_image(std::move(w));
      },
      "weight"_a, "uv"_a, "specular"_a, "position"_a,
      "A copy of weight (rgb, lod) where each seen, reflective miss (uv's vis <= 0) takes the lod\n"
      "of its nearest hit (3x3 chamfer distance) when within half that hit's footprint,\n"
      "2^(lod - 1) pixels (x 1.0824, the chamfer's largest overstatement): a glossy reflection\n"
      "blurs outward past its outline too; other misses within reach of a hit's footprint get 0.\n"
      "What composite_layers() does to its weight's lod.");
  m.def("marches", &py_marches, "{name: one-line description} of every march trace() accepts.");
  m.def("march_details", &py_march_details,
        "{name: {description, options: {keyword: meaning}, needs_mesh, uses_back_position, gl}}.");
  m.def("presets", &py_presets, "{name: trace() keyword arguments} of every preset.");
  m.def("preset_descriptions", &py_preset_descriptions, "{name: one line on what it measured}.");
}

}  // namespace glint::py
