// What both marches share: the G-buffer lookups, the projection and the
// near-plane clipping of native/src/cpu/ray.cpp, written in the same order.
// Needs common.glsl.

uniform sampler2D u_position;  // RGBA32F, read with texelFetch only
uniform sampler2D u_normal;    // RGBA32F, xyz used
uniform sampler2D u_specular;  // RGBA32F, read only when u_has_specular
uniform bool u_has_specular;   // TraceInputs::specular was given: skip non-reflective pixels

uniform float u_proj[16];   // projection, row-major, rows as printed
uniform double u_projd[16]; // the same in double, for the near-plane clipping
uniform int u_kind;         // 0 perspective, 1 orthographic, 2 general (glint::ProjectionKind)
uniform int u_eye_kind;     // 0 origin, 1 point, 2 direction (glint::EyeKind)
uniform vec3 u_eye;         // the eye point, or the unit direction of parallel view rays
uniform vec2 u_size;        // float(width), float(height)

uniform float u_max_distance;
uniform float u_thickness;
uniform int u_steps;

const int KIND_PERSPECTIVE = 0;
const int KIND_ORTHOGRAPHIC = 1;

// clip = P * (v, 1), one row at a time, left to right.
float clip_row(int r, vec3 v) {
  precise float c = u_proj[r * 4 + 0] * v.x + u_proj[r * 4 + 1] * v.y +
                    u_proj[r * 4 + 2] * v.z + u_proj[r * 4 + 3];
  return c;
}
vec4 clip_of(vec3 v) { return vec4(clip_row(0, v), clip_row(1, v), clip_row(2, v), clip_row(3, v)); }

double clip_rowd(int r, dvec3 v) {
  precise double c = u_projd[r * 4 + 0] * v.x + u_projd[r * 4 + 1] * v.y +
                     u_projd[r * 4 + 2] * v.z + u_projd[r * 4 + 3];
  return c;
}
// Signed distance-like value of the near plane test: clip z + clip w >= 0 in front.
double near_value(dvec3 v) {
  precise double r = clip_rowd(2, v) + clip_rowd(3, v);
  return r;
}

// Image::texel_at() on the frame (common.glsl's texel_in()).
bool texel_at(vec2 xy, out ivec2 q) { return texel_in(xy, u_size, q); }

// Fix 3 (docs/conventions.md): the nearest texel at floor(uv * size); off the image or on an
// unseen texel is a miss, and a miss reads as (0, 0, 0, 0).
bool fetch_position(vec2 uv, out vec4 p) {
  ivec2 q;
  if (texel_at(uv * u_size, q)) {
    vec4 t = texelFetch(u_position, q, 0);
    if (texel_seen(t)) {
      p = t;
      return true;
    }
  }
  p = vec4(0.0);
  return false;
}

// The view ray that reaches view point `from` (incident_direction() in native/src/cpu/ray.cpp),
// which for an orthographic camera is the same for every pixel. Apart from read_origin() so
// that the hiz march's outline samples can aim at points off the pixel's centre.
bool incident_direction(vec3 from, out vec3 unit_from) {
  if (u_eye_kind == 0) {
    if (dot3(from, from) == 0.0) return false;
    unit_from = normalize3(from);
  } else if (u_eye_kind == 1) {
    vec3 d = from - u_eye;
    if (dot3(d, d) == 0.0) return false;
    unit_from = normalize3(d);
  } else {
    unit_from = u_eye;
  }
  return finite_v3(unit_from);
}

// Fix 4 (docs/conventions.md): unseen pixels, zero or non-finite normals and a position at the
// eye report 0.
// The specular gate: the seed returns early where a pixel does not reflect.
bool read_origin(ivec2 px, out vec3 from, out vec3 unit_from, out vec3 normal) {
  if (u_has_specular && !is_reflective(texelFetch(u_specular, px, 0))) return false;
  vec4 p = texelFetch(u_position, px, 0);
  if (!texel_seen(p)) return false;
  vec3 n = texelFetch(u_normal, px, 0).xyz;
  if (!finite_v3(n) || dot3(n, n) == 0.0) return false;
  from = p.xyz;
  if (!incident_direction(from, unit_from)) return false;
  normal = normalize3(n);
  return finite_v3(normal);
}

// Fix 2 (docs/conventions.md): the ray length, shortened so the end stays in front of the near
// plane (clip z >= -w, w > 0). The crossing is solved in double; the float end
// point then lands on the plane give or take a rounding step, so it is checked
// and, while behind, pulled back by a shrink that starts at two float steps
// of the length and doubles each try, as clipped_length() on the CPU does.
// Negative where the origin itself is not in front.
float clipped_length(vec3 from, vec3 dir, float max_distance) {
  dvec3 fromd = dvec3(from);
  precise double n0 = near_value(fromd);
  if (!(n0 >= 0.0lf) || !(clip_rowd(3, fromd) > 0.0lf)) return -1.0;
  precise double len = double(max_distance);
  precise dvec3 endd = fromd + dvec3(dir) * len;
  precise double n1 = near_value(endd);
  if (n1 < 0.0lf) len = len * (n0 / (n0 - n1));
  precise float full = float(len);
  precise float lf = full;
  precise float shrink = 1.0 / 4194304.0;  // 2^-22
  for (int i = 0; i < 64; ++i) {
    precise vec3 e = from + dir * lf;
    dvec3 ed = dvec3(e);
    if (near_value(ed) >= 0.0lf && clip_rowd(3, ed) > 0.0lf) return lf;
    lf = full * (1.0 - shrink);
    shrink = shrink * 2.0 > 1.0 ? 1.0 : shrink * 2.0;
  }
  return 0.0;
}

// startFrag / endFrag of the seed: projected, divided, in pixel units.
bool to_frag(vec3 v, out vec2 frag) {
  vec4 c = clip_of(v);
  if (!(c.w > 0.0)) return false;
  precise float fx = (c.x / c.w * 0.5 + 0.5) * u_size.x;
  precise float fy = (c.y / c.w * 0.5 + 0.5) * u_size.y;
  frag = vec2(fx, fy);
  return finite_f(fx) && finite_f(fy);
}
