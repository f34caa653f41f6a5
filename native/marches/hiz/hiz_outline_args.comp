#version 430 core
// The dispatch arguments of the antialiased outlines' batches
// (hiz_outline.glsl) from the length of the list, on the GPU: no read-back.
// Per batch six words: hiz_outline_trace.comp's groups (an invocation per
// sample), then hiz_outline_resolve.comp's (one per listed pixel), each a
// row of at most 65535 groups and as many rows as that takes, as
// hiz_rays_args.comp sizes the reuse of rays'.
#include "common.glsl"
#include "hiz_outline.glsl"

layout(local_size_x = 1) in;

layout(std430, binding = 3) buffer HizOutlineArgs {
  uint args[];
};

uniform int u_batches;

void put(uint at, uint invocations) {
  uint groups = (invocations + OUTLINE_GROUP - 1u) / OUTLINE_GROUP;
  args[at] = min(groups, 65535u);
  args[at + 1u] = groups == 0u ? 0u : (groups + 65534u) / 65535u;
  args[at + 2u] = 1u;
}

void main() {
  for (int b = 0; b < u_batches; ++b) {
    uint first = uint(b) * uint(u_batch);
    uint n = count > first ? min(count - first, uint(u_batch)) : 0u;
    put(6u * uint(b), n * uint(u_per_pixel));
    put(6u * uint(b) + 3u, n);
  }
}
