#version 430 core
// Level 0 of the Hi-Z pyramid: each seen texel's nearest view distance over
// its footprint (its tangent plane at the four corners) and its farthest plus
// its thickness; (+inf, -inf) where nothing was seen. base_range() in
// march_hiz.cpp, operation for operation. The texel's plane
// normal (hiz_planes.glsl) is worked out here and written beside it for the
// walk: one pass over the G-buffer instead of two.
#include "common.glsl"
#include "fragment.glsl"
#include "trace_common.glsl"
#include "hiz_common.glsl"
#include "hiz_planes.glsl"

layout(location = 0) out vec2 out_range;
layout(location = 1) out vec4 out_normal;

void main() {
  ivec2 px = pixel_coord();
  vec3 plane = plane_normal(px);
  out_normal = vec4(plane, 0.0);
  vec4 p = imageLoad(u_position_img, px);
  if (!texel_seen(p)) {
    out_range = vec2(uintBitsToFloat(0x7f800000u), uintBitsToFloat(0xff800000u));
    return;
  }
  float d = -p.z;
  float t = texel_thickness(px, d);
  float lo = d;
  float hi = d;
  vec4 L;
  if (texel_plane(plane, p.xyz, L)) {
    precise float spread = FOOTPRINT_SPREAD * abs(d) + t;
    precise float sxs = 2.0 / u_size.x;
    precise float sys = 2.0 / u_size.y;
    // On the plane, the view point's z and w are affine in (sx, sy).
    precise float k = 1.0 / L.z;
    precise float al = -L.x * k;
    precise float be = -L.y * k;
    precise float ga = -L.w * k;
    precise float nx = u_inv[8] + u_inv[10] * al;
    precise float ny = u_inv[9] + u_inv[10] * be;
    precise float nc = u_inv[11] + u_inv[10] * ga;
    precise float dx = u_inv[12] + u_inv[14] * al;
    precise float dy = u_inv[13] + u_inv[14] * be;
    precise float dc = u_inv[15] + u_inv[14] * ga;
    for (int corner = 0; corner < 4; ++corner) {
      precise float sx = float(px.x + (corner & 1)) * sxs - 1.0;
      precise float sy = float(px.y + (corner >> 1)) * sys - 1.0;
      precise float cd = -((nx * sx + ny * sy + nc) / (dx * sx + dy * sy + dc));
      if (!finite_f(cd)) continue;
      precise float dlo = d - spread;
      precise float dhi = d + spread;
      cd = cd < dlo ? dlo : cd;
      cd = dhi < cd ? dhi : cd;
      lo = cd < lo ? cd : lo;
      hi = hi < cd ? cd : hi;
    }
  }
  precise float top = hi + t;
  out_range = vec2(lo, top);
}
