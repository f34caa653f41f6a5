// The split-sum environment BRDF (Karis 2013, "Real Shading in Unreal Engine
// 4"): the specular lobe integrated against a uniform environment is
// F0 * A + B, with A and B functions of N.V and roughness only. Glint
// tabulates them once per process, integrating the GGX lobe with the
// height-correlated Smith masking-shadowing term over a grid in the
// importance-sampling variables; both backends read the same table with the
// same bilinear rule. docs/look-core.md has the integrals and the error.
#pragma once
#include <vector>

namespace glint {

// Nodes per axis. Node (i, j): N.V = max(i / (N - 1), kEnvBrdfMinNdotV),
// perceptual roughness sqrt(alpha) = j / (N - 1).
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

}  // namespace glint
