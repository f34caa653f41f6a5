#version 430 core
// The G-buffer pass (the book's position, normal and material-specular
// passes in one): view-space triangles in, projected with the camera's
// matrix; every attribute is interpolated perspective-correctly to the
// pixel centres, as the CPU rasterizer's homogeneous barycentrics do.

layout(location = 0) in vec3 a_position;  // view space
layout(location = 1) in vec3 a_normal;    // view space, any length
layout(location = 2) in vec2 a_uv;        // only read with a normal map
layout(location = 3) in vec4 a_tangent;   // xyz + bitangent sign, likewise

uniform float u_proj[16];  // row-major, rows as printed

out vec3 v_position;
out vec3 v_normal;
out vec2 v_uv;
out vec4 v_tangent;

float clip_row(int r, vec3 v) {
  return u_proj[r * 4 + 0] * v.x + u_proj[r * 4 + 1] * v.y + u_proj[r * 4 + 2] * v.z + u_proj[r * 4 + 3];
}

void main() {
  v_position = a_position;
  v_normal = a_normal;
  v_uv = a_uv;
  v_tangent = a_tangent;
  gl_Position = vec4(clip_row(0, a_position), clip_row(1, a_position), clip_row(2, a_position),
                     clip_row(3, a_position));
}
