// Picking a backend by name: "cpu", "gl" or "auto" (GL when a context can be
// made, CPU otherwise). Backends are cached: the GL context is made once per
// process and reused across frames.
#pragma once
#include <memory>
#include <string>

#include "glint/stages.h"

namespace glint {

// Throws InvalidArgument("backend", ...) for an unknown name and
// BackendUnavailable when "gl" was asked for and cannot run here.
std::shared_ptr<Backend> get_backend(const std::string& name, int threads = 0);

// True when this build has the GL backend compiled in (GLINT_WITH_GL).
bool gl_compiled_in();

#ifdef GLINT_HAVE_GL
// Defined by the GL backend (native/src/gl). Throws BackendUnavailable.
std::shared_ptr<Backend> make_gl_backend();
#endif

}  // namespace glint
