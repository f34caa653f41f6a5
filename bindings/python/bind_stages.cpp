// Each stage of the pipeline on its own (glint::Backend's functions), for
// tests, tools and compositors that run a part of it.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <optional>
#include <string>

#include "bind.h"
#include "convert.h"
#include "glint/backend.h"
#include "glint/errors.h"
#include "glint/material.h"
#include "glint/options.h"

using namespace pybind11::literals;

namespace glint::py {
namespace {

const char* const kBackend = schema::backend.initial_name;

pyb::array_t<float> py_reflection_color(const pyb::handle& uv, const pyb::handle& color,
                                        const std::string& backend) {
  Image u = image_from_array(uv, "uv", 0.0f, 4), c = image_from_array(color, "color", 1.0f, 3);
  auto be = get_backend(backend);
  pyb::gil_scoped_release release;
  Image r = be->reflection_color(u, c);
  pyb::gil_scoped_acquire acquire;
  return array_from_image(std::move(r));
}

pyb::array_t<float> py_box_blur(const pyb::handle& image, int size, float separation,
                                const std::string& backend) {
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
}

pyb::array_t<float> py_specular_weight(const pyb::handle& position, const pyb::handle& normal,
                                       const pyb::handle& specular, const pyb::handle& projection,
                                       const std::string& backend) {
  const Image pos = image_from_array(position, "position", 1.0f, 4);
  const Image nrm = image_from_array(normal, "normal", 0.0f, 3);
  const Image spec = image_from_array(specular, "specular", 0.0f, 4);
  const Mat4 proj = projection_from_array(projection);
  auto be = get_backend(backend);
  pyb::gil_scoped_release release;
  Image r = be->specular_weight(pos, nrm, spec, proj);
  pyb::gil_scoped_acquire acquire;
  return array_from_image(std::move(r));
}

// The flat mirror's bound of the cone (glint::MirrorScale) from optional
// position and projection arguments: both, or neither (no bound).
struct OptionalMirror {
  std::optional<Image> position;
  MirrorScale scale;
  // The scale's position pointer is set here, not when made: the struct is
  // returned by value, and a pointer into it would then dangle.
  const MirrorScale* get() {
    if (!position) return nullptr;
    scale.position = &*position;
    return &scale;
  }
};

OptionalMirror optional_mirror(const pyb::handle& position, const pyb::handle& projection) {
  OptionalMirror m;
  if (position.is_none() != projection.is_none())
    throw InvalidArgument("position", "give position and projection together (the flat mirror's bound), or neither");
  if (position.is_none()) return m;
  m.position = image_from_array(position, "position", 1.0f, 4);
  m.scale = mirror_scale(*m.position, projection_from_array(projection));
  return m;
}

pyb::array_t<float> py_cone_blur(const pyb::handle& color, const pyb::handle& uv,
                                 const pyb::handle& specular, const pyb::handle& position,
                                 const pyb::handle& projection, const std::string& backend) {
  Image c = image_from_array(color, "reflection_color", 0.0f, 4);
  Image u = image_from_array(uv, "uv", 0.0f, 4);
  Image s = image_from_array(specular, "specular", 0.0f, 4);
  OptionalMirror m = optional_mirror(position, projection);
  auto be = get_backend(backend);
  pyb::gil_scoped_release release;
  Image r = be->cone_blur(c, u, s, m.get());
  pyb::gil_scoped_acquire acquire;
  return array_from_image(std::move(r));
}

pyb::array_t<float> py_cone_lod(const pyb::handle& uv, const pyb::handle& specular, const pyb::handle& position,
                                const pyb::handle& projection) {
  const Image u = image_from_array(uv, "uv", 0.0f, 4);
  const Image s = image_from_array(specular, "specular", 0.0f, 4);
  OptionalMirror m = optional_mirror(position, projection);
  Image r;
  {
    pyb::gil_scoped_release release;
    r = cone_lod(u, s, m.get());
  }
  pyb::array_t<float> out({r.height, r.width});
  float* o = out.mutable_data();
  for (int y = 0; y < r.height; ++y)
    for (int x = 0; x < r.width; ++x) o[static_cast<size_t>(y) * r.width + x] = r.px(x, y)[0];
  return out;
}

pyb::array_t<float> py_reflection(const pyb::handle& color, const pyb::handle& blurred,
                                  const pyb::handle& specular, const pyb::handle& weight,
                                  const std::string& backend) {
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
}

pyb::array_t<float> py_combine(const pyb::handle& base, const pyb::handle& reflection,
                               const std::string& mode, const pyb::handle& specular_base,
                               const pyb::handle& coverage, const std::string& backend) {
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
}

}  // namespace

void bind_stages(pyb::module_& m) {
  m.def("reflection_color", &py_reflection_color, "uv"_a, "color"_a, pyb::kw_only(), "backend"_a = kBackend,
        "Colour at the reflected uv (bilinear, clamp to edge), premultiplied by visibility.");
  m.def("box_blur", &py_box_blur, "image"_a, pyb::kw_only(), "size"_a = BlurOptions{}.size,
        "separation"_a = BlurOptions{}.separation, "backend"_a = kBackend,
        "(2 * size + 1)^2 box average of all four channels, taps `separation` pixels apart.");
  m.def("specular_weight", &py_specular_weight, "position"_a, "normal"_a, "specular"_a, "projection"_a,
        pyb::kw_only(), "backend"_a = kBackend,
        "Physical reflection weight: rgb = F0 * A + B (split-sum table at N.V and roughness),\n"
        "a = mean of the rgb; 0 where a pixel is unseen or does not reflect.");
  m.def("cone_blur", &py_cone_blur, "reflection_color"_a, "uv"_a, "specular"_a, pyb::kw_only(),
        "position"_a = pyb::none(), "projection"_a = pyb::none(), "backend"_a = kBackend,
        "The reflection colour blurred by each pixel's GGX cone: footprint 2 * ray length in\n"
        "pixels * cone tan, no wider than a flat mirror's when the G-buffer's position and the\n"
        "projection are given, read trilinearly from a 2x2 box mip chain.");
  m.def("cone_lod", &py_cone_lod, "uv"_a, "specular"_a, pyb::kw_only(), "position"_a = pyb::none(),
        "projection"_a = pyb::none(),
        "[H, W] level of detail of the cone blur per pixel: log2(2 * ray length in pixels *\n"
        "cone tan), no wider than a flat mirror's footprint (2 * 3D ray length * cone tan, in the\n"
        "pixels a view unit spans where the pixel's camera ray carried on by that length ends)\n"
        "when position and projection are given; 0 where that footprint is within a pixel, no\n"
        "hit was found or the pixel is a mirror or does not reflect (the rule cone_blur applies).");
  m.def("reflection", &py_reflection, "reflection_color"_a, "reflection_blur"_a, "specular"_a, pyb::kw_only(),
        "weight"_a = pyb::none(), "backend"_a = kBackend,
        "mix(colour, blurred, roughness) (the colour alone when reflection_blur is None) times\n"
        "weight (rgb on colour, a on alpha) or, without one, the specular amount.");
  m.def("combine", &py_combine, "color"_a, "reflection"_a, pyb::kw_only(), "mode"_a = schema::combine.initial_name,
        "specular_base"_a = pyb::none(), "coverage"_a = pyb::none(), "backend"_a = kBackend,
        "'over': base * (1 - a) + reflection.rgb (visibility once); 'seed': the demo's mix.\n"
        "With specular_base (and coverage, whose alpha is the share the trace found):\n"
        "max(base - specular_base * coverage.a, 0) + reflection.rgb.");

  m.def("gl_compiled_in", &gl_compiled_in, "True when this build has the OpenGL backend.");
  m.def(
      "backend_name", [](const std::string& backend) { return get_backend(backend)->name(); },
      "backend"_a = "auto",
      "The backend a name resolves to ('auto' -> 'gl' or 'cpu'); raises BackendUnavailable.");
}

}  // namespace glint::py
