// The split-sum environment BRDF (Karis 2013, "Real Shading in Unreal Engine
// 4"): the specular lobe integrated against a uniform environment is
// F0 * A + B, with A and B functions of N.V and roughness only (the Fresnel
// term's shape is a dielectric's, schema.h kFresnelShapeIor). Glint
// tabulates them once per process, integrating the GGX lobe with the
// height-correlated Smith masking-shadowing term over a grid in the
// importance-sampling variables; both backends read the same table with the
// same bilinear rule. docs/look-core.md has the integrals and the error.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

namespace glint {

// Nodes per axis. Node (i, j): N.V = max((i / (N - 1))^2, kEnvBrdfMinNdotV),
// perceptual roughness sqrt(alpha) = j / (N - 1). Both axes are square roots:
// a glossy lobe (alpha ~0.01) seen at a grazing angle changes A and B within
// N.V of about 2 alpha, which evenly spaced N.V nodes (1/31 apart) missed by
// 0.02; sqrt spacing puts the first nodes 0.001 and 0.004 from 0.
constexpr int kEnvBrdfSize = 32;
constexpr int kEnvBrdfU = 128;    // grid steps of the polar-angle CDF per node
constexpr int kEnvBrdfPhi = 16;   // grid steps of the azimuth over [0, pi] per node
constexpr double kEnvBrdfMinNdotV = 1e-4;  // N.V = 0 divides by zero; its limit is this close

// (A, B) of node (i, j) at [2 * (j * kEnvBrdfSize + i)]; built on first use
// (thread-safe): 8 M lobe evaluations, tens of milliseconds.
const std::vector<float>& env_brdf_table();

// A and B at any N.V in [0, 1] and GGX alpha in [0, 1] (clamped): bilinear
// between the nodes, as shaders/specular_weight.frag reads them.
void env_brdf(float n_dot_v, float alpha, float* a, float* b);

// env_brdf() on a table already at hand (env_brdf_table().data()), inline:
// the CPU weight asks it once per reflective pixel.
inline void env_brdf_lookup(const float* t, float n_dot_v, float alpha, float* a, float* b) {
  const int n = kEnvBrdfSize;
  const float scale = static_cast<float>(n - 1);
  auto clamp01 = [](float v) { return v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f; };
  const float x = std::sqrt(clamp01(n_dot_v)) * scale;
  const float y = std::sqrt(clamp01(alpha)) * scale;
  const int x0 = std::min(static_cast<int>(x), n - 2), y0 = std::min(static_cast<int>(y), n - 2);
  const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
  for (int c = 0; c < 2; ++c) {
    const float v00 = t[2 * (y0 * n + x0) + c], v10 = t[2 * (y0 * n + x0 + 1) + c];
    const float v01 = t[2 * ((y0 + 1) * n + x0) + c], v11 = t[2 * ((y0 + 1) * n + x0 + 1) + c];
    const float bottom = v00 * (1.0f - fx) + v10 * fx;
    const float top = v01 * (1.0f - fx) + v11 * fx;
    (c == 0 ? *a : *b) = bottom * (1.0f - fy) + top * fy;
  }
}

}  // namespace glint
