// The GLSL passes of shaders/, compiled into the library by
// cmake/EmbedShaders.cmake (the definitions are generated at build time).
#pragma once
#include <string>

namespace glint::gl {

struct EmbeddedShader {
  const char* name;    // path under shaders/, e.g. "trace_seed.frag"
  const char* source;  // includes resolved, with `#line <line> <file number>` directives
};

// nullptr when no entry point of that name was embedded.
const EmbeddedShader* find_embedded_shader(const std::string& name);

// The shader file behind a #line source-string number, nullptr when unknown.
const char* embedded_file_name(int number);

}  // namespace glint::gl
