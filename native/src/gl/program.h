// Building GL programs from the embedded shaders, with compiler messages that
// point at the original file and line under shaders/.
#pragma once
#include <string>
#include <vector>

#include "gl/embedded_shaders.h"
#include "gl/gl_api.h"

namespace glint::gl {

// Rewrites the "<string>:<line>" / "<string>(<line>)" locations that GLSL
// compilers put at the start of a message line (Mesa "0:12(5): error",
// NVIDIA "0(12) : error", AMD "ERROR: 0:12:") into "<file>:<line>", using the
// source-string numbers of the embedder's #line directives. String 0 is the
// #version line of `entry`. `file_name` maps the other numbers: the
// library's embedded list, or a test's own (native/tests/CMakeLists.txt).
using FileNameFn = const char* (*)(int number);
std::string map_shader_log(const std::string& log, const std::string& entry,
                           FileNameFn file_name = embedded_file_name);

// Compiles one embedded entry point ("trace_seed.frag"); the stage comes from
// the extension. Throws glint::Error with the mapped log on failure.
GLuint compile_embedded(const Api& gl, const std::string& entry);

// Compiles `source` as if it were the embedded entry `entry` (for tests of the
// error mapping). Throws glint::Error with the mapped log on failure.
GLuint compile_source(const Api& gl, GLenum stage, const std::string& source,
                      const std::string& entry, FileNameFn file_name = embedded_file_name);
// The stage of an entry point, from its extension (.vert, .frag, .comp, .geom).
GLenum stage_of(const std::string& entry);

// Links the given embedded entry points into a program. Throws glint::Error.
GLuint link_program(const Api& gl, const std::vector<std::string>& entries);

}  // namespace glint::gl
