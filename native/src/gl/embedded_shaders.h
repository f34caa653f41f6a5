// The GLSL passes of shaders/, compiled into the library by
// cmake/EmbedShaders.cmake (the definitions are generated at build time).
#pragma once
#include <string>

namespace glint::gl {

struct EmbeddedShader {
  const char* name;    // what passes and includes call it, e.g. "trace_seed.frag"
  const char* path;    // where the file is, from the repository root, for messages
  const char* source;  // includes resolved, with `#line <line> <file number>` directives
};

// nullptr when no entry point of that name was embedded.
const EmbeddedShader* find_embedded_shader(const std::string& name);

// The shader file behind a #line source-string number, from the repository
// root ("shaders/common.glsl"), nullptr when unknown.
const char* embedded_file_name(int number);

}  // namespace glint::gl
