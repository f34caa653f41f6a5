# Embeds the GLSL passes of shaders/ into a generated C++ source, so the
# library never reads shader files at run time (nothing depends on the working
# directory or on where the library was installed).
#
# Two roles in one file:
#  * included from CMake: glint_embed_shaders() adds the custom command that
#    regenerates the .cpp whenever any listed shader (or this script) changes;
#  * run with `cmake -P` by that command: does the embedding.
#
# Entry points (.vert, .frag, .comp) are stored with their `#include "x.glsl"`
# lines resolved here, at build time. Every listed file gets a number (its
# position in the list, from 1) and the expanded text carries `#line <line>
# <number>` directives, so a compiler message "3:17(2): error" means line 17 of
# the third listed file; the runtime turns that back into "common.glsl:17".
# GLSL's #line takes no file names, hence the numbers.

set(_GLINT_EMBED_SCRIPT "${CMAKE_CURRENT_LIST_FILE}")

# glint_embed_shaders(<target> OUTPUT <file.cpp> BASE_DIR <dir> FILES <relative paths>...
#                     [EXTRA <name>=<absolute path>...] [NAMESPACE <c++ namespace>])
# EXTRA files live outside BASE_DIR (schema.glsl, written by the build; a
# march folder's shaders) and are embedded and included by name as if they
# were in BASE_DIR. NAMESPACE (default glint::gl) lets a test
# embed shaders of its own without clashing with the library's.
function(glint_embed_shaders target)
  cmake_parse_arguments(ARG "" "OUTPUT;BASE_DIR;NAMESPACE" "FILES;EXTRA" ${ARGN})
  if(NOT ARG_NAMESPACE)
    set(ARG_NAMESPACE "glint::gl")
  endif()
  set(deps "")
  foreach(f IN LISTS ARG_FILES)
    list(APPEND deps "${ARG_BASE_DIR}/${f}")
  endforeach()
  foreach(g IN LISTS ARG_EXTRA)
    string(REGEX REPLACE "^[^=]*=" "" gpath "${g}")
    list(APPEND deps "${gpath}")
  endforeach()
  # A list cannot cross the command line intact; '|' never appears in a path we accept.
  string(REPLACE ";" "|" files_arg "${ARG_FILES}")
  string(REPLACE ";" "|" generated_arg "${ARG_EXTRA}")
  add_custom_command(
    OUTPUT "${ARG_OUTPUT}"
    COMMAND "${CMAKE_COMMAND}"
            "-DGLINT_SHADER_DIR=${ARG_BASE_DIR}"
            "-DGLINT_SHADER_FILES=${files_arg}"
            "-DGLINT_SHADER_GENERATED=${generated_arg}"
            "-DGLINT_SHADER_NAMESPACE=${ARG_NAMESPACE}"
            "-DGLINT_SHADER_ROOT=${PROJECT_SOURCE_DIR}"
            "-DGLINT_SHADER_OUTPUT=${ARG_OUTPUT}"
            -P "${_GLINT_EMBED_SCRIPT}"
    DEPENDS ${deps} "${_GLINT_EMBED_SCRIPT}"
    COMMENT "Embedding GLSL shaders into ${ARG_OUTPUT}"
    VERBATIM)
  target_sources(${target} PRIVATE "${ARG_OUTPUT}")
endfunction()

if(NOT CMAKE_SCRIPT_MODE_FILE OR NOT DEFINED GLINT_SHADER_OUTPUT)
  return()
endif()

# ---------------------------------------------------------------------------
# Script mode (cmake -P runs with no policies set: ask for today's behaviour).
cmake_policy(VERSION 3.18)

string(REPLACE "|" ";" _files "${GLINT_SHADER_FILES}")
string(REPLACE "|" ";" _generated "${GLINT_SHADER_GENERATED}")
set(_delim "glint_shader")

# EXTRA files: listed after the others, read from where they are.
foreach(g IN LISTS _generated)
  string(REGEX MATCH "^[^=]*" _gname "${g}")
  string(REGEX REPLACE "^[^=]*=" "" _gpath "${g}")
  set(_PATH_${_gname} "${_gpath}")
  list(APPEND _files "${_gname}")
endforeach()

# File number for #line: position in the list, from 1 (0 is the #version line's string).
set(_id 0)
foreach(f IN LISTS _files)
  math(EXPR _id "${_id} + 1")
  set(_ID_${f} ${_id})
endforeach()

# Number of the line that `offset` characters into `text` starts on (1-based).
function(_glint_line_at text offset out)
  string(SUBSTRING "${text}" 0 ${offset} prefix)
  string(REGEX MATCHALL "\n" nl "${prefix}")
  list(LENGTH nl n)
  math(EXPR n "${n} + 1")
  set(${out} ${n} PARENT_SCOPE)
endfunction()

# Text of `name` with its includes expanded; `depth` guards against cycles.
function(_glint_expand name depth out)
  if(depth GREATER 16)
    message(FATAL_ERROR "EmbedShaders: #include nesting deeper than 16 at ${name} (a cycle?)")
  endif()
  if(NOT DEFINED _ID_${name})
    message(FATAL_ERROR "EmbedShaders: \"${name}\" is included but not listed among the shader "
                        "files in native/CMakeLists.txt or a march folder's glint_march_shaders()")
  endif()
  set(path "${GLINT_SHADER_DIR}/${name}")
  if(DEFINED _PATH_${name})
    set(path "${_PATH_${name}}")
  endif()
  if(NOT EXISTS "${path}")
    message(FATAL_ERROR "EmbedShaders: ${path} does not exist")
  endif()
  file(READ "${path}" rest)
  string(REPLACE "\r\n" "\n" rest "${rest}")
  get_filename_component(dir "${name}" DIRECTORY)
  set(id ${_ID_${name}})
  set(done "")
  set(line_base 0)  # lines of this file already moved into `done`
  while(TRUE)
    # Only an #include at the start of a line (after blanks) counts.
    string(REGEX MATCH "(^|\n)[ \t]*#[ \t]*include[ \t]+\"([^\"\n]+)\"[^\n]*" m "${rest}")
    if(m STREQUAL "")
      break()
    endif()
    set(inc "${CMAKE_MATCH_2}")
    string(FIND "${rest}" "${m}" pos)
    if(m MATCHES "^\n")  # keep the newline that ends the previous line
      math(EXPR pos "${pos} + 1")
      string(SUBSTRING "${m}" 1 -1 m)
    endif()
    string(LENGTH "${m}" mlen)
    _glint_line_at("${rest}" ${pos} local_line)
    math(EXPR inc_line "${line_base} + ${local_line}")
    # Relative to the including file, named by its path under shaders/.
    get_filename_component(inc_abs "${GLINT_SHADER_DIR}/${dir}/${inc}" ABSOLUTE)
    get_filename_component(root_abs "${GLINT_SHADER_DIR}" ABSOLUTE)
    file(RELATIVE_PATH inc_name "${root_abs}" "${inc_abs}")
    math(EXPR child_depth "${depth} + 1")
    _glint_expand("${inc_name}" ${child_depth} inc_text)
    math(EXPR next_line "${inc_line} + 1")
    string(SUBSTRING "${rest}" 0 ${pos} before)
    math(EXPR after_pos "${pos} + ${mlen}")
    string(SUBSTRING "${rest}" ${after_pos} -1 rest)
    # The directive's own line becomes the included text; the newline that
    # ended it stays in `rest`, after a #line that resumes this file.
    string(APPEND done "${before}// begin ${inc_name}\n${inc_text}\n#line ${next_line} ${id}")
    math(EXPR line_base "${inc_line} - 1")
  endwhile()
  string(APPEND done "${rest}")
  if(depth EQUAL 0)
    # The #version directive must stay first: number the lines after it.
    string(REGEX MATCH "^[ \t]*#[ \t]*version[^\n]*\n" ver "${done}")
    if(ver STREQUAL "")
      message(FATAL_ERROR "EmbedShaders: ${name} must start with a #version line")
    endif()
    string(LENGTH "${ver}" vlen)
    string(SUBSTRING "${done}" ${vlen} -1 body)
    set(done "${ver}#line 2 ${id}\n${body}")
  else()
    if(done MATCHES "(^|\n)[ \t]*#[ \t]*version")
      message(FATAL_ERROR "EmbedShaders: included file ${name} must not have a #version line")
    endif()
    set(done "#line 1 ${id}\n${done}")
  endif()
  set(${out} "${done}" PARENT_SCOPE)
endfunction()

set(_entries "")
set(_names "")
set(_using "")
if(NOT GLINT_SHADER_NAMESPACE STREQUAL "glint::gl")
  set(_using "using glint::gl::EmbeddedShader;\n")
endif()
foreach(f IN LISTS _files)
  # Messages name the file where it is, from the repository root.
  if(DEFINED _PATH_${f})
    set(_abs "${_PATH_${f}}")
  else()
    set(_abs "${GLINT_SHADER_DIR}/${f}")
  endif()
  file(RELATIVE_PATH _where "${GLINT_SHADER_ROOT}" "${_abs}")
  if(_where MATCHES "^\\.\\./")
    set(_where "${_abs}")
  endif()
  set(_WHERE_${f} "${_where}")
  string(APPEND _names "    \"${_where}\",\n")
  if(NOT f MATCHES "\\.(vert|frag|comp|geom)$")
    continue()
  endif()
  _glint_expand("${f}" 0 _text)
  string(FIND "${_text}" ")${_delim}\"" _bad)
  if(NOT _bad EQUAL -1)
    message(FATAL_ERROR "EmbedShaders: ${f} contains the raw-string delimiter )${_delim}\"")
  endif()
  string(APPEND _entries "    {\"${f}\", \"${_WHERE_${f}}\", R\"${_delim}(${_text})${_delim}\"},\n")
endforeach()

set(_cpp "// Generated by cmake/EmbedShaders.cmake from shaders/: edit the shaders, not this file.
#include \"gl/embedded_shaders.h\"

#include <cstring>

namespace ${GLINT_SHADER_NAMESPACE} {
${_using}
namespace {

const EmbeddedShader kShaders[] = {
${_entries}};

// Index = the source-string number in the #line directives.
const char* const kFileNames[] = {
    \"\",
${_names}};

}  // namespace

const EmbeddedShader* find_embedded_shader(const std::string& name) {
  for (const auto& s : kShaders)
    if (name == s.name) return &s;
  return nullptr;
}

const char* embedded_file_name(int number) {
  const int n = static_cast<int>(sizeof(kFileNames) / sizeof(kFileNames[0]));
  return number > 0 && number < n ? kFileNames[number] : nullptr;
}

}  // namespace ${GLINT_SHADER_NAMESPACE}
")

# Rewrite only on change, so an unrelated edit does not recompile the library.
if(EXISTS "${GLINT_SHADER_OUTPUT}")
  file(READ "${GLINT_SHADER_OUTPUT}" _old)
  if(_old STREQUAL _cpp)
    return()
  endif()
endif()
file(WRITE "${GLINT_SHADER_OUTPUT}" "${_cpp}")
