// What every screen-space march of the CPU backend shares: small float
// vector maths in the shaders' operation order, the pixel's own ray, the
// near-plane clip (fix 2 of docs/conventions.md) and the projection to pixel coordinates.
#pragma once
#include <cmath>

#include "march.h"

namespace glint::cpu {

struct V3 {
  float x, y, z;
};
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(V3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline float dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline float length(V3 a) { return std::sqrt(dot(a, a)); }
inline V3 normalize(V3 a) { return a * (1.0f / length(a)); }
inline V3 reflect(V3 i, V3 n) { return i - n * (2.0f * dot(n, i)); }
inline bool finite(float v) { return v - v == 0.0f; }
inline bool finite(V3 v) { return finite(v.x) && finite(v.y) && finite(v.z); }
inline float clamp01(float v) { return v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v); }
inline float mixf(float a, float b, float t) { return a * (1.0f - t) + b * t; }

// clip = P * (v, 1), in float as the shader does it.
inline void clip_of(const float* P, V3 v, float c[4]) {
  for (int r = 0; r < 4; ++r) c[r] = P[r * 4 + 0] * v.x + P[r * 4 + 1] * v.y + P[r * 4 + 2] * v.z + P[r * 4 + 3];
}

inline double clip_row(const double* P, int r, double x, double y, double z) {
  return P[r * 4 + 0] * x + P[r * 4 + 1] * y + P[r * 4 + 2] * z + P[r * 4 + 3];
}

// View distance: how far in front of the camera a point is.
inline float view_distance(V3 v) { return -v.z; }

// Reads the pixel's own position and normal; false where the seed reports 0.
// FIX 4: unseen pixels, zero or non-finite normals, and a position at the eye
// (which has no direction) give (0, 0, 0, 0) instead of NaN.
bool read_origin(const MarchSetup& s, int x, int y, V3& from, V3& unit_from, V3& normal);
// The unit incident direction of the camera's view ray through view point
// `from` (the setup's eye kind); false where it has none.
bool incident_direction(const MarchSetup& s, V3 from, V3& unit_from);

// FIX 2: the length of the ray, shortened so that its end stays on or in
// front of the near plane (clip z >= -w) with w > 0. The plane test is
// linear along the ray, so the crossing is solved in double. The float end
// point then lands on the plane give or take a rounding step, so it is
// checked and, while behind, pulled back by a shrink that starts at a few
// float steps and doubles each time: ordinary rays lose ~1e-7 of their
// length, while the extremes (a point 1e7 away with a 1e-4 near plane) still
// reach a valid end within a few dozen tries.
// Returns a negative length where the origin itself is not in front.
float clipped_length(const MarchSetup& s, V3 from, V3 dir, float max_distance);

// startFrag / endFrag of the seed: projected, divided, to pixel coordinates.
inline bool to_frag(const float* P, V3 v, float w, float h, float frag[2]) {
  float c[4];
  clip_of(P, v, c);
  if (!(c[3] > 0.0f)) return false;
  frag[0] = (c[0] / c[3] * 0.5f + 0.5f) * w;
  frag[1] = (c[1] / c[3] * 0.5f + 0.5f) * h;
  return finite(frag[0]) && finite(frag[1]);
}

}  // namespace glint::cpu
