// What the Hi-Z base level and the Hi-Z walk share: the tangent plane of a
// texel in NDC and its depth there, and a texel's thickness. Ports of the
// helpers in march_hiz.cpp, same operation order.
// Needs common.glsl and trace_common.glsl. Its constants (FOOTPRINT_SPREAD,
// CELL_NUDGE, EDGE_FADE ...) are schema.glsl's.

uniform float u_inv[16];          // inverse projection, row-major (cpu::HizCamera)
uniform sampler2D u_back;         // RGBA32F back-face layer, read when u_has_back
uniform bool u_has_back;

bool normal_usable(vec3 n) { return finite_v3(n) && (n.x != 0.0 || n.y != 0.0 || n.z != 0.0); }

// known_thickness() and texel_thickness() in march_hiz.cpp.
float known_thickness(ivec2 px, float d) {
  if (!u_has_back) return -1.0;
  vec4 b = texelFetch(u_back, px, 0);
  return texel_seen(b) && -b.z > d ? -b.z - d : -1.0;
}

float texel_thickness(ivec2 px, float d) {
  float t = known_thickness(px, d);
  return t > 0.0 ? t : u_thickness;
}

// L . (sx, sy, sz, 1) = 0 is the texel's plane in NDC; false without a usable
// normal or for a plane seen exactly edge-on.
bool texel_plane(vec3 n, vec3 p, out vec4 L) {
  L = vec4(0.0);
  if (!normal_usable(n)) return false;
  precise float k = n.x * p.x + n.y * p.y + n.z * p.z;
  for (int c = 0; c < 4; ++c) {
    precise float v = n.x * u_inv[c] + n.y * u_inv[4 + c] + n.z * u_inv[8 + c] - k * u_inv[12 + c];
    L[c] = v;
  }
  return L.z != 0.0;
}

float plane_depth(vec4 L, float sx, float sy) {
  precise float sz = -(L.x * sx + L.y * sy + L.w) / L.z;
  precise float num = u_inv[8] * sx + u_inv[9] * sy + u_inv[10] * sz + u_inv[11];
  precise float den = u_inv[12] * sx + u_inv[13] * sy + u_inv[14] * sz + u_inv[15];
  precise float r = -(num / den);
  return r;
}
