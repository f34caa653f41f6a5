#version 430 core
// The (2 size + 1)^2 box blur of all four channels, as two passes (clamp to
// edge and linear taps both factor per axis):
//   u_pass 0: horizontal sums of 2 size + 1 taps, not yet divided;
//   u_pass 1: vertical sums of those, times u_norm, inside u_region; every
//             pixel outside the region is copied from the source.
// Taps sit `separation` pixels apart and interpolate linearly between the two
// nearest texels, clamped to the edge: tap_1d() in native/src/cpu/cpu_backend.cpp.
#include "common.glsl"
#include "fragment.glsl"

uniform sampler2D u_src;    // pass 0: the image; pass 1: the image, for the copy
uniform sampler2D u_horiz;  // pass 1: the horizontal sums
uniform int u_pass;
uniform int u_size;
uniform float u_separation;
uniform float u_norm;      // 1 / (2 size + 1)^2
uniform ivec4 u_region;    // x0, y0, x1, y1 (half-open): where pass 1 blurs

layout(location = 0) out vec4 out_color;

// Position p in texels along one axis (integer p = a texel centre).
vec4 tap(sampler2D tex, ivec2 px, int axis, float p, int n) {
  float f0 = floor(p);
  precise float a = p - f0;
  int i0 = clamp(int(f0), 0, n - 1);
  int i1 = clamp(int(f0) + 1, 0, n - 1);
  ivec2 c0 = px;
  ivec2 c1 = px;
  c0[axis] = i0;
  c1[axis] = i1;
  vec4 v0 = texelFetch(tex, c0, 0);
  vec4 v1 = texelFetch(tex, c1, 0);
  if (a == 0.0) return v0;
  precise vec4 r = v0 * (1.0 - a) + v1 * a;
  return r;
}

void main() {
  ivec2 px = pixel_coord();
  ivec2 size = textureSize(u_src, 0);
  if (u_pass == 0) {
    precise vec4 acc = vec4(0.0);
    for (int i = -u_size; i <= u_size; ++i) {
      precise float p = float(px.x) + float(i) * u_separation;
      acc += tap(u_src, px, 0, p, size.x);
    }
    out_color = acc;
    return;
  }
  if (px.x < u_region.x || px.y < u_region.y || px.x >= u_region.z || px.y >= u_region.w) {
    out_color = texelFetch(u_src, px, 0);
    return;
  }
  precise vec4 acc = vec4(0.0);
  for (int j = -u_size; j <= u_size; ++j) {
    precise float p = float(px.y) + float(j) * u_separation;
    acc += tap(u_horiz, px, 1, p, size.y);
  }
  precise vec4 r = acc * u_norm;
  out_color = r;
}
