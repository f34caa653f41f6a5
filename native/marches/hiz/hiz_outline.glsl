// The hiz march's antialiased outlines (native/src/cpu/outline.cpp and
// march_hiz.cpp on the CPU; docs/hiz.md), what their passes share. hiz_outline_find.comp lists the pixels
// on a reflection's outline; hiz_outline_args.comp sizes the two dispatches
// of each batch; hiz_outline_trace.comp writes the reports of their extra
// rays (u_per_pixel per listed pixel) and hiz_outline_resolve.comp filters
// them with the centre's into the frame. The samples are kept for a batch of
// at most u_batch listed pixels at a time (listed pixels u_first ...), so
// that their buffer stays within GL_MAX_SHADER_STORAGE_BLOCK_SIZE however
// large the frame: most frames are one batch, and a batch past the end of
// the list is a dispatch of no groups.

// The host resets count to 0 before hiz_outline_find.comp.
layout(std430, binding = 1) buffer HizOutline {
  uint count;
  uint outline_pixel[];  // x | y << 16 | BESIDE_HIDDEN_BIT, in no particular order
};

// Sample j of the batch's listed pixel i at u_per_pixel * i + j.
layout(std430, binding = 2) buffer HizOutlineSamples {
  vec4 sample_report[];
};

uniform int u_per_pixel;  // min(TraceOptions::antialias, 4)
uniform int u_first;      // the batch's first listed pixel
uniform int u_batch;      // listed pixels per batch, at most

// The trace and resolve passes' work group size.
const uint OUTLINE_GROUP = 64u;

// The batch's listed pixels. A dispatch of the batch has groups only when
// count > u_first (hiz_outline_args.comp).
uint batch_pixels() { return min(count - uint(u_first), uint(u_batch)); }

// The invocation's index in an indirect dispatch of rows of groups.
uint invocation_index() {
  return (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * OUTLINE_GROUP + gl_LocalInvocationID.x;
}

// Set on a listed pixel that or one of whose 4-neighbours entered a hidden
// side (resolve_outline()'s one_hit_uv). Free: GL_MAX_TEXTURE_SIZE is at most
// 32768, so y < 2^15.
const uint BESIDE_HIDDEN_BIT = 0x80000000u;
ivec2 unpack_pixel(uint p) { return ivec2(int(p & 0xffffu), int((p >> 16) & 0x7fffu)); }

// report_of() in native/src/cpu/outline.h: a hit (visibility in the fourth channel), a
// plain miss, a hidden side entered (ENTERED_HIDDEN), or anything else (an
// occluder found late), left as it is.
const int REPORT_MISS = 0;
const int REPORT_HIT = 1;
const int REPORT_OTHER = 2;
const int REPORT_ENTERED = 3;
int report_of(vec4 o) {
  if (o.w > 0.0) return REPORT_HIT;
  if (o.w == ENTERED_HIDDEN) return REPORT_ENTERED;
  return o.z == 0.0 && o.w == 0.0 ? REPORT_MISS : REPORT_OTHER;
}

// opposite_reports() in native/src/cpu/outline.h: a hit against a miss or a
// hidden side entered, the pairs a pixel's rays can resolve.
bool opposite_reports(int a, int b) {
  return a == REPORT_HIT ? (b == REPORT_MISS || b == REPORT_ENTERED) : (b == REPORT_HIT && a != REPORT_OTHER);
}
