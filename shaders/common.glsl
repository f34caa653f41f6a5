// Shared helpers of every pass. Most arithmetic here is written out term by
// term, in the order native/src/cpu uses, and marked `precise`: a compiler
// may otherwise fuse a*b+c into one FMA or reassociate sums, and the trace
// is chaotic enough (a hit or a miss) that one rounding difference changes
// a pixel. Non-finite tests use the bit pattern, because `x - x == 0.0` or
// isnan() may be folded away by an optimizing compiler.
//
// Every pass that includes this file gets the constants of
// native/include/glint/schema.h (schema.glsl, written at build time).
#include "schema.glsl"

bool finite_f(float v) { return (floatBitsToUint(v) & 0x7f800000u) != 0x7f800000u; }
bool finite_v3(vec3 v) { return finite_f(v.x) && finite_f(v.y) && finite_f(v.z); }
bool finite_v4(vec4 v) { return finite_v3(v.xyz) && finite_f(v.w); }

float clamp01(float v) { return v < 0.0 ? 0.0 : (v > 1.0 ? 1.0 : v); }

// mix() may be lowered as a + t * (b - a); the CPU computes a * (1 - t) + b * t.
float mixf(float a, float b, float t) {
  precise float r = a * (1.0 - t) + b * t;
  return r;
}

float dot3(vec3 a, vec3 b) {
  precise float r = a.x * b.x + a.y * b.y + a.z * b.z;
  return r;
}

float length3(vec3 a) {
  precise float r = sqrt(dot3(a, a));
  return r;
}

vec3 normalize3(vec3 a) {
  precise float inv = 1.0 / length3(a);
  precise vec3 r = a * inv;
  return r;
}

vec3 reflect3(vec3 i, vec3 n) {
  precise float k = 2.0 * dot3(n, i);
  precise vec3 r = i - n * k;
  return r;
}

// The view distance of a view-space point: Blender's camera looks down -Z.
float view_distance(vec3 v) { return -v.z; }

// The G-buffer's two tests, as glint/material.h defines them for the CPU.
// A position texel counts as seen when w > 0 and every channel is finite
// (non-finite values are data meaning "nothing seen").
bool texel_seen(vec4 p) { return p.w > 0.0 && finite_v4(p); }

// Image::texel_at() for an image of `size` texels: the texel q holding point
// xy, in pixels; false off the image, NaN included. The bounds are checked on
// the floats, before converting: int() of a float beyond int's range is
// undefined.
bool texel_in(vec2 xy, vec2 size, out ivec2 q) {
  precise vec2 f = floor(xy);
  q = ivec2(0);
  if (!(f.x >= 0.0 && f.y >= 0.0 && f.x < size.x && f.y < size.y)) return false;
  q = ivec2(f);
  return true;
}

// glint::incident_toward(): the incident direction toward view point p,
// unnormalised, by the camera eye's kind (0 origin, 1 point, 2 direction).
vec3 incident_toward(int eye_kind, vec3 eye, vec3 p) {
  return eye_kind == 0 ? p : (eye_kind == 1 ? p - eye : eye);
}

// The seed's specular amount: the mean of the specular rgb.
float specular_amount(vec4 s) {
  precise float amount = (s.r + s.g + s.b) / 3.0;
  return amount;
}

// A pixel reflects when its specular amount is positive (and finite).
bool is_reflective(vec4 s) {
  precise float amount = specular_amount(s);
  return amount > 0.0 && finite_f(amount);
}
