#include "glint/metrics.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "glint/errors.h"
#include "glint/stages.h"

namespace glint {
namespace {

double percentile(std::vector<float>& v, double q) {
  if (v.empty()) return 0.0;
  const size_t k = static_cast<size_t>(std::floor(q * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

}  // namespace

Accuracy compare_uv(const Image& uv, const Image& exact, const Image* color, const Image* specular,
                    const AccuracyOptions& opt) {
  require_image(uv, "uv");
  require_same_size(uv, "uv", exact, "exact");
  if (color) require_same_size(uv, "uv", *color, "color");
  if (specular) require_same_size(uv, "uv", *specular, "specular");
  if (!(opt.tolerance_px >= 0.0f) || !std::isfinite(opt.tolerance_px))
    throw InvalidArgument("tolerance_px", "expected a finite number >= 0, got " + std::to_string(opt.tolerance_px));
  if (!(opt.report_above >= 0.0f) || !std::isfinite(opt.report_above))
    throw InvalidArgument("report_above", "expected a finite number >= 0");

  Accuracy a;
  a.disagreement = Image(uv.width, uv.height);
  std::vector<float> errors;
  const double w = uv.width, h = uv.height, tol2 = double(opt.tolerance_px) * opt.tolerance_px;
  // A NaN visibility reports nothing: `>` is false for it.
  for (int y = 0; y < uv.height; ++y) {
    for (int x = 0; x < uv.width; ++x) {
      const float* p = uv.px(x, y);
      const float* e = exact.px(x, y);
      const bool rep = p[2] > opt.report_above, vis = e[2] > opt.report_above;
      a.reported += rep;
      a.exact_visible += vis;
      float* d = a.disagreement.px(x, y);
      if (!rep && !vis) continue;
      d[3] = 1.0f;
      if (rep && !vis) {
        ++a.false_reflections;
        d[0] = 1.0f;
        continue;
      }
      if (!rep) {
        d[2] = 1.0f;
        continue;
      }
      const double du = (double(p[0]) - e[0]) * w, dv = (double(p[1]) - e[1]) * h;
      const double e2 = du * du + dv * dv;
      errors.push_back(std::isfinite(e2) ? static_cast<float>(std::sqrt(e2)) : INFINITY);
      if (e2 <= tol2) {
        ++a.correct;
        d[1] = 1.0f;
      } else {
        d[0] = d[1] = 1.0f;
      }
    }
  }
  a.found = a.correct;
  if (a.reported > 0) a.precision = double(a.correct) / double(a.reported);
  if (a.exact_visible > 0) a.recall = double(a.found) / double(a.exact_visible);
  if (!errors.empty()) {
    a.max_px = *std::max_element(errors.begin(), errors.end());
    a.p95_px = percentile(errors, 0.95);
    a.median_px = percentile(errors, 0.5);
  }
  if (color) {
    // The reflection layer each buffer makes, with the pipeline's own stage.
    auto cpu = make_cpu_backend();
    const Image mine = cpu->reflection_color(uv, *color);
    const Image truth = cpu->reflection_color(exact, *color);
    double sum = 0.0;
    for (int y = 0; y < uv.height; ++y) {
      for (int x = 0; x < uv.width; ++x) {
        const bool counted = specular ? is_reflective(specular->px(x, y))
                                      : (uv.px(x, y)[2] > opt.report_above || exact.px(x, y)[2] > opt.report_above);
        if (!counted) continue;
        const float* m = mine.px(x, y);
        const float* t = truth.px(x, y);
        const double diff = (std::fabs(double(m[0]) - t[0]) + std::fabs(double(m[1]) - t[1]) +
                             std::fabs(double(m[2]) - t[2])) / 3.0;
        if (std::isfinite(diff)) sum += diff;
        ++a.image_pixels;
      }
    }
    a.image_mae = a.image_pixels > 0 ? sum / double(a.image_pixels) : 0.0;
  }
  return a;
}

}  // namespace glint
