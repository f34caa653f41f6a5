// The list of pixels the hiz march's reuse of rays left to trace: appended by
// trace_hiz_fill.comp, sized for the dispatch by hiz_rays_args.comp, walked by
// trace_hiz_list.comp. The first three words are glDispatchComputeIndirect's
// arguments, so the dispatch is sized on the GPU without a read-back. The
// host resets the first four words to (0, 1, 1, 0) before the fill pass.
layout(std430, binding = 0) buffer HizRays {
  uint groups_x;
  uint groups_y;
  uint groups_z;
  uint count;
  uint pixel[];  // x | y << 16, in no particular order
};

// trace_hiz_list.comp's work group size; the 64 lanes of a wave on a GPU.
const uint RAYS_PER_GROUP = 64u;
