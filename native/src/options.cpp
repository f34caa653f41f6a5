#include "glint/options.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "glint/errors.h"

namespace glint {
namespace {

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

void require_range(const char* name, double v, double lo, double hi) {
  if (!std::isfinite(v) || v < lo || v > hi) {
    throw InvalidArgument(name, "expected a finite number in [" + num(lo) + ", " + num(hi) +
                                    "], got " + num(v));
  }
}

}  // namespace

void validate(const TraceOptions& o) {
  require_range("max_distance", o.max_distance, 0.0, kMaxDistanceLimit);
  require_range("resolution", o.resolution, 0.0, 1.0);
  require_range("thickness", o.thickness, 0.0, 1e30);
  if (o.steps < 0 || o.steps > kMaxSteps) {
    throw InvalidArgument("steps", "expected an integer in [0, " + std::to_string(kMaxSteps) +
                                       "], got " + std::to_string(o.steps));
  }
}

void validate(const BlurOptions& o) {
  if (o.size < 0 || o.size > kMaxBlurSize) {
    throw InvalidArgument("blur_size", "expected an integer in [0, " +
                                           std::to_string(kMaxBlurSize) + "], got " +
                                           std::to_string(o.size));
  }
  require_range("blur_separation", o.separation, 1.0, kMaxBlurSeparation);
}

void validate(const PipelineOptions& o) {
  validate(o.trace);
  validate(o.blur);
  validate_threads(o.threads);
}

void validate_threads(int threads) {
  if (threads < 0 || threads > kMaxThreads) {
    throw InvalidArgument("threads", "expected 0 (all hardware threads) to " +
                                         std::to_string(kMaxThreads) + ", got " +
                                         std::to_string(threads));
  }
}

Combine parse_combine(const std::string& name) {
  if (name == "over") return Combine::Over;
  if (name == "seed") return Combine::Seed;
  throw InvalidArgument("combine", "expected \"over\" or \"seed\", got \"" + name + "\"");
}

const char* to_string(Combine c) { return c == Combine::Over ? "over" : "seed"; }

Weighting parse_weighting(const std::string& name) {
  if (name == "physical") return Weighting::Physical;
  if (name == "seed") return Weighting::Seed;
  throw InvalidArgument("weighting", "expected \"physical\" or \"seed\", got \"" + name + "\"");
}

const char* to_string(Weighting w) { return w == Weighting::Physical ? "physical" : "seed"; }

BlurMode parse_blur_mode(const std::string& name) {
  if (name == "cone") return BlurMode::Cone;
  if (name == "box") return BlurMode::Box;
  throw InvalidArgument("blur", "expected \"cone\" or \"box\", got \"" + name + "\"");
}

const char* to_string(BlurMode b) { return b == BlurMode::Cone ? "cone" : "box"; }

Blocked parse_blocked(const std::string& name) {
  if (name == "miss") return Blocked::Miss;
  if (name == "occluder") return Blocked::Occluder;
  throw InvalidArgument("blocked", "expected \"miss\" or \"occluder\", got \"" + name + "\"");
}

const char* to_string(Blocked b) { return b == Blocked::Miss ? "miss" : "occluder"; }

}  // namespace glint
