#version 430 core
// One level of the cone blur's chain: the mean of the 2x2 block of the level
// below (u_src, an image of that level alone), the last row or
// column repeated where that level is one texel wide. cpu/look.cpp reduce().
#include "common.glsl"
#include "fragment.glsl"

layout(rgba32f, binding = 0) uniform readonly image2D u_src;
uniform ivec4 u_sizes;  // (width, height) of the level below; this level's width, height

layout(location = 0) out vec4 out_color;

void main() {
  ivec2 px = pixel_coord();
  int x0 = 2 * px.x, x1 = min(2 * px.x + 1, u_sizes.x - 1);
  int y0 = 2 * px.y, y1 = min(2 * px.y + 1, u_sizes.y - 1);
  vec4 a = imageLoad(u_src, ivec2(x0, y0));
  vec4 b = imageLoad(u_src, ivec2(x1, y0));
  vec4 c = imageLoad(u_src, ivec2(x0, y1));
  vec4 d = imageLoad(u_src, ivec2(x1, y1));
  precise vec4 r = ((a + b) + (c + d)) * 0.25;
  out_color = r;
}
