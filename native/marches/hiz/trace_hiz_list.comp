#version 430 core
// The hiz march for the pixels the reuse of rays left to trace (the list in
// hiz_rays.glsl), a ray per invocation, so that every lane of a SIMD group
// walks one. Fragments would instead run a 2x2 or 4x4 block of the screen,
// whose settled pixels idle for as long as the block's longest walk.
#include "common.glsl"
#include "trace_common.glsl"
#include "hiz_common.glsl"
#include "hiz_walk.glsl"
#include "hiz_rays.glsl"

layout(local_size_x = 64) in;  // RAYS_PER_GROUP

layout(rgba32f, binding = 0) uniform writeonly image2D u_out;

void main() {
  uint i = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * RAYS_PER_GROUP +
           gl_LocalInvocationID.x;
  // The last group's tail, and with several rows the last row's.
  if (i >= count) return;
  uint p = pixel[i];
  ivec2 c = ivec2(int(p & 0xffffu), int(p >> 16));
  imageStore(u_out, c, trace_pixel(c));
}
