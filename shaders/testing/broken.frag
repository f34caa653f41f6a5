#version 430 core
// Deliberately broken, never used by a pass: native/tests/test_gl.cpp compiles
// it to check that a compile error names this file and the line below the
// marker, after an #include has shifted the line numbers of the expanded text.
#include "../common.glsl"

layout(location = 0) out vec4 out_color;

void main() {
  // GLINT_TEST_ERROR_NEXT_LINE
  out_color = vec4(undeclared_on_purpose);
}
