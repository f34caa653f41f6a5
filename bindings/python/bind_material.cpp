// The specular buffer's encoding and the look's formulas, one value at a
// time: what the add-on's material mapping and the tests check against.
#include <pybind11/pybind11.h>

#include "bind.h"
#include "glint/brdf.h"
#include "glint/material.h"

using namespace pybind11::literals;

namespace glint::py {

void bind_material(pyb::module_& m) {
  m.def("shininess_to_alpha", &shininess_to_alpha, "shininess"_a,
        "shininess / MAX_SHININESS, 0 below 0: the specular buffer's alpha (schema());\n"
        "above 1 the gloss range (hardness past 511), +inf a mirror (1).");
  m.def("shininess_from_hardness", &shininess_from_hardness, "hardness"_a,
        "Blender Internal hardness to shininess: hardness / HARDNESS_PER_SHININESS (schema()).");
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
      "GGX alpha of a specular-buffer alpha a: sqrt(2 / (h + 2)) at hardness\n"
      "h = a * HARDNESS_PER_SHININESS * MAX_SHININESS, 0 at a == 1 (a mirror) or\n"
      "a not finite; above 1 the gloss range.");
  m.def("cone_tan", &cone_tan, "alpha"_a,
        "tan of the reflection cone's half-angle for GGX alpha: 2 a / (1 - a^2), capped at MAX_CONE_TAN.");
}

}  // namespace glint::py
