// Internal face of the GL backend, for tests and benchmarks. The public entry
// point is glint::make_gl_backend() (backend.h).
#pragma once
#include <memory>
#include <string>

#include "glint/stages.h"

namespace glint::gl {

// A new GL backend with its own worker thread and context, loading EGL from
// `egl_library` — not the process-wide cached one. For tests that need a
// fresh context (the EGL-missing path). Throws BackendUnavailable.
std::shared_ptr<Backend> create_gl_backend(const std::string& egl_library);

// "EGL surfaceless (Mesa), OpenGL 4.5 (Core Profile) Mesa 22.3.6, llvmpipe ..."
// for a backend made by make_gl_backend() / create_gl_backend().
std::string describe(const Backend& gl_backend);

// Compiles and links the embedded entry point `entry` (with fullscreen.vert
// when it is a fragment shader) on the backend's context; throws glint::Error
// carrying the compiler log mapped to shaders/<file>:<line>.
void compile_for_test(Backend& gl_backend, const std::string& entry);
// Compiles `source` as the entry `entry` (no link), for shaders a test embeds
// itself; `file_name` maps its #line numbers to files.
void compile_for_test(Backend& gl_backend, const std::string& entry, const std::string& source,
                      const char* (*file_name)(int number));

}  // namespace glint::gl
