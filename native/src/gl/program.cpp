#include "gl/program.h"

#include <cctype>
#include <sstream>

#include "gl/embedded_shaders.h"
#include "glint/errors.h"

namespace glint::gl {

GLenum stage_of(const std::string& entry) {
  auto ends = [&](const char* ext) {
    const std::string e(ext);
    return entry.size() >= e.size() && entry.compare(entry.size() - e.size(), e.size(), e) == 0;
  };
  if (ends(".vert")) return GL_VERTEX_SHADER;
  if (ends(".frag")) return GL_FRAGMENT_SHADER;
  if (ends(".comp")) return GL_COMPUTE_SHADER;
  if (ends(".geom")) return GL_GEOMETRY_SHADER;
  throw Error("glint GL: cannot tell the shader stage of \"" + entry + "\" from its extension");
}

namespace {

// Where an entry point's file is, for messages: the embedded path, or under
// shaders/ for one the library does not hold (a test's own).
std::string entry_path(const std::string& entry) {
  const EmbeddedShader* s = find_embedded_shader(entry);
  return s ? s->path : "shaders/" + entry;
}

// Reads a run of digits at s[i]; false when there is none.
bool digits_at(const std::string& s, size_t& i, long& value) {
  const size_t start = i;
  value = 0;
  while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i])) && i - start < 9)
    value = value * 10 + (s[i++] - '0');
  return i > start;
}

std::string map_line(const std::string& line, const std::string& entry, FileNameFn file_name) {
  // The first "<n>:<m>" or "<n>(<m>)" that is not part of a longer word.
  for (size_t i = 0; i < line.size(); ++i) {
    if (!std::isdigit(static_cast<unsigned char>(line[i]))) continue;
    if (i > 0 && (std::isalnum(static_cast<unsigned char>(line[i - 1])) || line[i - 1] == '_' ||
                  line[i - 1] == '.'))
      continue;
    size_t j = i;
    long string_no = 0, line_no = 0;
    digits_at(line, j, string_no);
    if (j >= line.size()) return line;
    const char sep = line[j];
    if (sep != ':' && sep != '(') {
      i = j;
      continue;
    }
    size_t k = j + 1;
    if (!digits_at(line, k, line_no)) {
      i = j;
      continue;
    }
    if (sep == '(') {
      if (k >= line.size() || line[k] != ')') {
        i = j;
        continue;
      }
      ++k;
    }
    const char* listed = string_no == 0 ? nullptr : file_name(static_cast<int>(string_no));
    if (string_no != 0 && !listed) return line;
    const std::string file = string_no == 0 ? entry_path(entry) : listed;
    return line.substr(0, i) + file + ":" + std::to_string(line_no) + line.substr(k);
  }
  return line;
}

std::string stage_name(GLenum stage) {
  switch (stage) {
    case GL_VERTEX_SHADER: return "vertex";
    case GL_FRAGMENT_SHADER: return "fragment";
    case GL_COMPUTE_SHADER: return "compute";
    case GL_GEOMETRY_SHADER: return "geometry";
    default: return "shader";
  }
}

}  // namespace

std::string map_shader_log(const std::string& log, const std::string& entry, FileNameFn file_name) {
  std::istringstream in(log);
  std::string line, out;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    out += map_line(line, entry, file_name);
    out += '\n';
  }
  return out;
}

GLuint compile_source(const Api& gl, GLenum stage, const std::string& source,
                      const std::string& entry, FileNameFn file_name) {
  GLuint shader = gl.CreateShader(stage);
  if (!shader) throw Error("glint GL: glCreateShader failed for " + entry_path(entry));
  const char* text = source.c_str();
  gl.ShaderSource(shader, 1, &text, nullptr);
  gl.CompileShader(shader);
  GLint ok = GL_FALSE;
  gl.GetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    GLint length = 0;
    gl.GetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::string log(static_cast<size_t>(length > 0 ? length : 1), '\0');
    gl.GetShaderInfoLog(shader, static_cast<GLsizei>(log.size()), nullptr, &log[0]);
    log.resize(std::char_traits<char>::length(log.c_str()));
    gl.DeleteShader(shader);
    throw Error("glint GL: compiling the " + stage_name(stage) + " shader " + entry_path(entry) +
                " failed:\n" + map_shader_log(log, entry, file_name));
  }
  return shader;
}

GLuint compile_embedded(const Api& gl, const std::string& entry) {
  const EmbeddedShader* s = find_embedded_shader(entry);
  if (!s)
    throw Error("glint GL: no embedded shader named \"" + entry +
                "\" (list it in native/CMakeLists.txt, or a march's with glint_march_shaders() in its folder)");
  return compile_source(gl, stage_of(entry), s->source, entry);
}

GLuint link_program(const Api& gl, const std::vector<std::string>& entries) {
  std::vector<GLuint> shaders;
  try {
    for (const auto& e : entries) shaders.push_back(compile_embedded(gl, e));
  } catch (...) {
    for (GLuint s : shaders) gl.DeleteShader(s);
    throw;
  }
  GLuint program = gl.CreateProgram();
  for (GLuint s : shaders) gl.AttachShader(program, s);
  gl.LinkProgram(program);
  for (GLuint s : shaders) {
    gl.DetachShader(program, s);
    gl.DeleteShader(s);
  }
  GLint ok = GL_FALSE;
  gl.GetProgramiv(program, GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    GLint length = 0;
    gl.GetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
    std::string log(static_cast<size_t>(length > 0 ? length : 1), '\0');
    gl.GetProgramInfoLog(program, static_cast<GLsizei>(log.size()), nullptr, &log[0]);
    log.resize(std::char_traits<char>::length(log.c_str()));
    gl.DeleteProgram(program);
    std::string names;
    for (const auto& e : entries) names += (names.empty() ? "" : " + ") + entry_path(e);
    throw Error("glint GL: linking " + names + " failed:\n" +
                map_shader_log(log, entries.empty() ? "" : entries.back()));
  }
  return program;
}

}  // namespace glint::gl
