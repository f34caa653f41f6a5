#include "glint/presets.h"

#include <cstring>
#include <string>

#include "glint/errors.h"

namespace glint {
namespace {

TraceOptions trace_of(March m, float max_distance, float resolution, int steps, float thickness) {
  TraceOptions o;
  o.march = m;
  o.max_distance = max_distance;
  o.resolution = resolution;
  o.steps = steps;
  o.thickness = thickness;
  return o;
}

}  // namespace

const std::vector<Preset>& presets() {
  // max_distance and thickness are the seed's defaults: they describe the
  // scene, not the quality, and a user sets them for the scene's scale.
  static const std::vector<Preset> table = {
      {"draft", "Hi-Z walk on a short budget: the cheapest that keeps most hits",
       trace_of(March::Hiz, 15.0f, 0.3f, 2, 0.5f)},
      {"balanced", "Hi-Z walk with the budget past which recall stops rising",
       trace_of(March::Hiz, 15.0f, 0.3f, 6, 0.5f)},
      {"high", "Hi-Z walk with a budget no measured ray exhausts",
       trace_of(March::Hiz, 15.0f, 0.3f, 32, 0.5f)},
  };
  return table;
}

const Preset& preset(const char* name) {
  std::string names;
  for (const Preset& p : presets()) {
    if (std::strcmp(p.name, name) == 0) return p;
    names += (names.empty() ? "" : ", ") + std::string(p.name);
  }
  throw InvalidArgument("preset", "expected one of " + names + ", got \"" + std::string(name) + "\"");
}

}  // namespace glint
