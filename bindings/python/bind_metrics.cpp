// glint_core.compare: a reflected-uv buffer against the exact march's.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <optional>

#include "convert.h"
#include "glint/metrics.h"
#include "glint/stages.h"

namespace pyb = pybind11;
using namespace pybind11::literals;

namespace glint::py {

void bind_metrics(pyb::module_& m) {
  m.def(
      "compare",
      [](const pyb::handle& uv, const pyb::handle& exact, const pyb::handle& color,
         const pyb::handle& specular, float tolerance_px) {
        const Image u = image_from_array(uv, "uv", 0.0f, 3);
        const Image e = image_from_array(exact, "exact", 0.0f, 3);
        std::optional<Image> c, s;
        if (!color.is_none()) c = image_from_array(color, "color", 1.0f, 3);
        if (!specular.is_none()) s = image_from_array(specular, "specular", 1.0f, 4);
        AccuracyOptions opt;
        opt.tolerance_px = tolerance_px;
        Accuracy a;
        {
          pyb::gil_scoped_release release;
          a = compare_uv(u, e, c ? &*c : nullptr, s ? &*s : nullptr, opt);
        }
        pyb::dict out;
        out["precision"] = a.precision;
        out["recall"] = a.recall;
        out["reported"] = a.reported;
        out["exact_visible"] = a.exact_visible;
        out["correct"] = a.correct;
        out["false_reflections"] = a.false_reflections;
        out["median_px"] = a.median_px;
        out["p95_px"] = a.p95_px;
        out["max_px"] = a.max_px;
        out["image_mae"] = a.image_mae >= 0.0 ? pyb::cast(a.image_mae) : pyb::none();
        out["image_pixels"] = a.image_pixels;
        out["tolerance_px"] = tolerance_px;
        out["disagreement"] = array_from_image(std::move(a.disagreement));
        return out;
      },
      "uv"_a, "exact"_a, pyb::kw_only(), "color"_a = pyb::none(), "specular"_a = pyb::none(),
      "tolerance_px"_a = 1.5f,
      "Accuracy of a reflected-uv buffer against march='exact' (docs/conventions.md): precision and recall\n"
      "within tolerance_px, median/p95/max pixel error where both report, false reflections,\n"
      "and with color the mean absolute error of the reflection colour over reflective\n"
      "pixels (specular amount > 0 when specular is given). 'disagreement' is an image:\n"
      "red false, green right, blue missed, yellow reported off by more than the tolerance.");
}

}  // namespace glint::py
