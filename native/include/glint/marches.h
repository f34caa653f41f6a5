// The table of marches: every way Glint can turn a G-buffer into a
// reflected-uv buffer, in one place. The bindings, the command-line tool, the
// add-on (through glint_core.marches()), the tests and the sweeps all read
// it; an unknown name is an error everywhere. Each march is a folder of
// native/marches/ whose march.cpp returns its row, registered by one line of
// native/marches/CMakeLists.txt; docs/marches.md shows one added.
#pragma once
#include <string>
#include <vector>

#include "glint/image.h"
#include "glint/options.h"

namespace glint {

struct TraceInputs;
namespace gl {
class GlState;  // the GL backend's state (native/src/gl/gl_state.h)
}

// One trace option as a march uses it: which keyword, and what it means there.
struct MarchKnob {
  const char* option;   // a TraceOptions field, by its Python keyword name
  const char* meaning;  // what the value does for this march
};

// A whole frame of one march on the CPU: the reference every backend is held to.
using CpuTraceFn = Image (*)(const TraceInputs& in, const TraceOptions& opt, int threads);
// A whole frame of one march on the GL backend, through its own passes.
using GlTraceFn = Image (*)(gl::GlState& gl, const TraceInputs& in, const TraceOptions& opt);

struct MarchInfo {
  // Its position in the registration list (the built-in ones have an
  // enumerator of that value); set by the registry, not by the row.
  March id = March::Seed;
  const char* name = nullptr;         // the `march=` keyword value
  const char* description = nullptr;  // one line, for help texts and tooltips
  std::vector<MarchKnob> knobs;       // the options it reads; the others are ignored
  bool needs_mesh = false;            // reads TraceInputs::mesh (the scene's triangles)
  // What the CPU implementation allocates beside its output, for the memory
  // budget (glint/memory.h): bytes per pixel, and per triangle of the mesh.
  unsigned scratch_per_pixel = 0;
  unsigned scratch_per_triangle = 0;
  bool uses_back_position = false;  // reads TraceInputs::back_position where given
  CpuTraceFn cpu = nullptr;         // the CPU implementation
  // The GL backend's fragment program (embedded by name), or nullptr when
  // the march has no GPU form: backend="gl" then runs `cpu` and says so.
  const char* gl_program = nullptr;
  // Where the GPU form is more than gl_program drawn once over the frame
  // (the hiz march builds its pyramid first, and may trace a quarter of the
  // pixels and list the rest): the passes that run instead of that draw,
  // defined in the march's folder and built with the GL backend only (set
  // the field under #ifdef GLINT_HAVE_GL). nullptr: the one draw.
  GlTraceFn gl_trace = nullptr;
};

// Every march, in the order help texts list them: the registration order.
const std::vector<MarchInfo>& march_table();
// The rows in registration order, as written (id unset): generated from
// native/marches/CMakeLists.txt. march_table() is the one to read.
std::vector<MarchInfo> registered_marches();
const MarchInfo& march_info(March m);
// Throws InvalidArgument("march", ...) listing the known names.
const MarchInfo& march_info(const std::string& name);
inline March parse_march(const std::string& name) { return march_info(name).id; }
inline const char* to_string(March m) { return march_info(m).name; }

// "seed", "linear", ... joined with `sep`, for messages and help texts.
std::string march_names(const char* sep = ", ");

}  // namespace glint
