#version 430 core
// Deliberately broken through its include; see broken_include.glsl.
#include "broken_include.glsl"

layout(location = 0) out vec4 out_color;

void main() { out_color = vec4(broken_helper()); }
