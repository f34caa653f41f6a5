// Named points on the speed / accuracy dial, chosen from the measured fronts
// in docs/sweeps/ (docs/presets.md has the figures). The bindings, the CLI
// and the add-on read them from here.
#pragma once
#include <vector>

#include "glint/options.h"

namespace glint {

struct Preset {
  const char* name;
  const char* description;  // one line, with what it measured
  TraceOptions trace;
};

const std::vector<Preset>& presets();
// Throws InvalidArgument("preset", ...) listing the known names.
const Preset& preset(const char* name);

}  // namespace glint
