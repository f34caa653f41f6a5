#version 430 core
// The hiz march's antialiased outlines, the extra rays (sample_start() and
// subpixel_ray() in march_hiz.cpp, same operations in the same order): an
// invocation per sample of a listed pixel of the batch (hiz_outline.glsl),
// so that every lane walks a ray, as in trace_hiz_list.comp. A sample whose
// ray cannot be made keeps the centre's report.
#include "common.glsl"
#include "trace_common.glsl"
#include "hiz_common.glsl"
#include "hiz_walk.glsl"
#include "hiz_outline.glsl"

layout(local_size_x = 64) in;  // OUTLINE_GROUP

layout(rgba32f, binding = 0) uniform readonly image2D u_out;  // the traced frame: the centres' reports

// kAaOffset in native/src/cpu/outline.h: the rotated grid (glint/schema.h), sample k's
// offset from the pixel's centre in pixels.
const vec2 AA_OFFSET[4] = vec2[4](vec2(-ANTIALIAS_NEAR, -ANTIALIAS_FAR), vec2(ANTIALIAS_FAR, -ANTIALIAS_NEAR),
                                  vec2(ANTIALIAS_NEAR, ANTIALIAS_FAR), vec2(-ANTIALIAS_FAR, ANTIALIAS_NEAR));

// The ray of pixel px from `offset` pixels off its centre, into the g_
// globals: from where the view ray through that point meets the texel's
// tangent plane, mirrored about the pixel's shading normal. False where the
// plane is seen edge-on or the point would leave the texel's depth range.
bool make_subpixel_ray(ivec2 px, vec2 offset) {
  vec3 from, unit_from, normal;
  if (!read_origin(px, from, unit_from, normal)) return false;
  vec4 L;
  if (!texel_plane(imageLoad(u_planes, px).xyz, imageLoad(u_position_img, px).xyz, L)) return false;
  precise float ox = 0.5 + offset.x;
  precise float oy = 0.5 + offset.y;
  precise float sx = (float(px.x) + ox) * (2.0 / u_size.x) - 1.0;
  precise float sy = (float(px.y) + oy) * (2.0 / u_size.y) - 1.0;
  precise float sz = -(L.x * sx + L.y * sy + L.w) / L.z;
  precise float v0 = u_inv[0] * sx + u_inv[1] * sy + u_inv[2] * sz + u_inv[3];
  precise float v1 = u_inv[4] * sx + u_inv[5] * sy + u_inv[6] * sz + u_inv[7];
  precise float v2 = u_inv[8] * sx + u_inv[9] * sy + u_inv[10] * sz + u_inv[11];
  precise float v3 = u_inv[12] * sx + u_inv[13] * sy + u_inv[14] * sz + u_inv[15];
  precise float ax = v0 / v3;
  precise float ay = v1 / v3;
  precise float az = v2 / v3;
  vec3 at = vec3(ax, ay, az);
  float d = -from.z;
  precise float off_plane = abs(-az - d);
  precise float lim = FOOTPRINT_SPREAD * abs(d);
  if (!finite_v3(at) || !(off_plane <= lim)) return false;
  if (!incident_direction(at, unit_from)) return false;
  return make_ray_from(at, unit_from, normal);
}

void main() {
  uint i = invocation_index();
  uint k = uint(u_per_pixel);
  // The last group's tail, and with several rows the last row's.
  if (i >= batch_pixels() * k) return;
  ivec2 c = unpack_pixel(outline_pixel[uint(u_first) + i / k]);
  vec4 o = make_subpixel_ray(c, AA_OFFSET[i % k]) ? trace_ray(c) : imageLoad(u_out, c);
  sample_report[i] = o;
}
