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
      {"draft", "Hi-Z walk, 5 cells per level: ~0.91 recall, 0.99+ precision on the analytic scenes",
       trace_of(March::Hiz, 15.0f, 0.3f, 5, 0.5f)},
      {"balanced", "Hi-Z walk, 10 cells per level: past it recall gains under 1% (docs/marches.md)",
       trace_of(March::Hiz, 15.0f, 0.3f, 10, 0.5f)},
      {"high", "Hi-Z walk, 16 cells per level: no ray of the analytic scenes runs out of budget",
       trace_of(March::Hiz, 15.0f, 0.3f, 16, 0.5f)},
      {"exact", "Every mirror ray traced against the scene's triangles on the CPU: needs mesh",
       trace_of(March::Exact, 15.0f, 0.3f, 10, 0.5f)},
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
