#version 430 core
// The back-face layer (RasterInputs::back_layer): of the back-facing
// triangles, the nearest one strictly behind the front layer's surface at
// each pixel, as the CPU rasterizer's second pass keeps it. Same vertex
// shader and depth mapping as gbuffer.frag.
in vec3 v_position;

uniform sampler2D u_front;  // the front pass's position target
uniform float u_depth_base;
uniform float u_depth_scale;

// With RasterInputs::back_albedo, the material albedo of the triangle that
// wins the back layer, looked up as gbuffer.frag looks up its specular.
layout(std430, binding = 0) readonly buffer TriangleMaterial { int triangle_material[]; };
// Per material: (albedo r, g, b, 1).
layout(std430, binding = 2) readonly buffer MaterialAlbedo { vec4 material_albedo[]; };
uniform int u_first_triangle;  // of this draw: gl_PrimitiveID counts from the draw's first
uniform bool u_back_albedo;    // only then is there a target for it

// BACK_SEPARATION: how far behind the front a back face must lie.
#include "schema.glsl"

layout(location = 0) out vec4 out_back;
layout(location = 1) out vec4 out_albedo;

void main() {
  if (gl_FrontFacing) discard;
  vec4 front = texelFetch(u_front, ivec2(gl_FragCoord.xy), 0);
  if (!(front.w > 0.0)) discard;
  float d = -v_position.z;
  float fd = -front.z;
  if (!(d > fd + BACK_SEPARATION * abs(fd))) discard;
  out_back = vec4(v_position, 1.0);
  out_albedo = u_back_albedo ? material_albedo[triangle_material[u_first_triangle + gl_PrimitiveID]]
                             : vec4(0.0);
  gl_FragDepth = (d - u_depth_base) * u_depth_scale;
}
