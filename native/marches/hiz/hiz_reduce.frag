#version 430 core
// One level of the Hi-Z pyramid from the level below it (u_src, an image of
// that level alone): min of the nearest, max of the farthest. The last texel
// of a row or column also takes what an odd size leaves over, so that with
// GL's floor(size / 2) levels no texel is lost.
#include "fragment.glsl"

layout(rg32f, binding = 0) uniform readonly image2D u_src;
uniform ivec4 u_sizes;  // source level width, height; this level's width, height

layout(location = 0) out vec2 out_range;

void main() {
  ivec2 px = pixel_coord();
  ivec2 u_src_size = u_sizes.xy;
  ivec2 u_dst_size = u_sizes.zw;
  int x0 = 2 * px.x;
  int y0 = 2 * px.y;
  int x1 = px.x == u_dst_size.x - 1 ? u_src_size.x - 1 : min(2 * px.x + 1, u_src_size.x - 1);
  int y1 = px.y == u_dst_size.y - 1 ? u_src_size.y - 1 : min(2 * px.y + 1, u_src_size.y - 1);
  float lo = uintBitsToFloat(0x7f800000u);
  float hi = uintBitsToFloat(0xff800000u);
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      vec2 c = imageLoad(u_src, ivec2(x, y)).xy;
      lo = c.x < lo ? c.x : lo;
      hi = hi < c.y ? c.y : hi;
    }
  }
  out_range = vec2(lo, hi);
}
