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
      {"draft",
       "Hi-Z walk, 5 cells per level. Blender samples, 960x540: recall 0.99 (0.64 on normal-mapped "
       "water), precision 0.92-0.99 with the back layer; ~0.5x the seed's time (docs/presets.md)",
       trace_of(March::Hiz, 15.0f, 0.3f, 5, 0.5f)},
      {"balanced",
       "Hi-Z walk, 10 cells per level, the knee of the fronts. Blender samples, 960x540: recall 0.99 "
       "(0.91 on normal-mapped water), precision 0.92-0.99 with the back layer; 0.4-0.6x the seed's time",
       trace_of(March::Hiz, 15.0f, 0.3f, 10, 0.5f)},
      {"high",
       "Hi-Z walk, 16 cells per level: no ray runs out of budget. Blender samples, 960x540: recall 0.99 "
       "(0.95 on normal-mapped water), precision as balanced; about balanced's time",
       trace_of(March::Hiz, 15.0f, 0.3f, 16, 0.5f)},
      {"exact",
       "Every mirror ray traced against the scene's triangles, on the CPU; needs mesh. Precision and "
       "recall 1 by definition; 0.2-0.5x the seed's time on the samples' few thousand triangles",
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
