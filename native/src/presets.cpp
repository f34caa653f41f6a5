#include "glint/presets.h"

#include <cstring>
#include <string>

#include "glint/errors.h"

namespace glint {
namespace {

// A preset sets the quality only; max_distance and thickness keep the
// defaults (glint/schema.h): they describe the scene, not the quality, and a
// user sets them for the scene's scale.
TraceOptions trace_of(March m, float resolution, int steps, int antialias) {
  TraceOptions o;
  o.march = m;
  o.resolution = resolution;
  o.steps = steps;
  o.antialias = antialias;
  return o;
}

}  // namespace

const std::vector<Preset>& presets() {
  static const std::vector<Preset> table = {
      {"draft",
       "Hi-Z walk, 5 cells per level, a quarter of the rays traced and reused where neighbours agree. "
       "1080p analytic scenes: recall 0.91-0.94, precision 0.999; ~0.2x the seed's CPU time "
       "(docs/marches.md)",
       trace_of(March::Hiz, 0.3f, 5, 0)},
      {"balanced",
       "Hi-Z walk, 10 cells per level, a quarter of the rays traced and reused where neighbours agree. "
       "1080p analytic scenes: recall 0.98-0.99, precision 0.999; ~0.2x the seed's CPU time. Blender "
       "samples: precision 0.92-0.99 with the back layer (docs/presets.md). Outlines antialiased with 4 more "
       "rays per outline pixel",
       trace_of(March::Hiz, 0.3f, 10, 4)},
      {"high",
       "Hi-Z walk, 16 cells per level, every pixel's own ray: no ray runs out of budget and none is "
       "reused; outlines antialiased with 4 more rays per outline pixel. About 1.6x balanced's CPU time, a "
       "third of the seed's (docs/marches.md)",
       trace_of(March::Hiz, 1.0f, 16, 4)},
      {"exact",
       "Every mirror ray traced against the scene's triangles, on the CPU; needs mesh. Precision and "
       "recall 1 by definition (ray by ray); outlines antialiased with 4 more rays per outline pixel. "
       "0.2-0.5x the seed's time on the samples' few thousand triangles",
       trace_of(March::Exact, 0.3f, 10, 4)},
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
