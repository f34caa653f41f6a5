// G-buffers from geometry: the book's position, normal and material-specular
// passes over view-space triangles. Both backends implement it; the CPU one
// is the exact reference (edge functions, perspective-correct interpolation
// at pixel centres), the GL one is what runs on a GPU.
#pragma once
#include <cstdint>
#include <vector>

#include "glint/image.h"
#include "glint/projection.h"

namespace glint {

struct Material {
  float specular[3] = {0.0f, 0.0f, 0.0f};  // specular colour, linear
  float shininess = 0.0f;  // the book's units: 0..127.75 (Blender Internal hardness / 4)
  int normal_map = -1;     // index into RasterInputs::normal_maps, -1 for none
  float albedo[3] = {0.0f, 0.0f, 0.0f};  // diffuse colour, linear
};

// A triangle soup in view space (Blender camera space: -Z forward).
struct Mesh {
  std::vector<float> positions;    // 9 per triangle: three corners, xyz
  std::vector<float> normals;      // 9 per triangle: corner normals, xyz
  std::vector<int32_t> material;   // 1 per triangle: index into the material table
  std::vector<float> uvs;          // 6 per triangle, only needed where a material has a normal map
  std::vector<float> tangents;     // 12 per triangle (xyz + bitangent sign), likewise
  size_t triangle_count() const { return material.size(); }
};

struct RasterInputs {
  const Mesh& mesh;
  const std::vector<Material>& materials;
  const std::vector<Image>& normal_maps;  // tangent space, encoded rgb = n * 0.5 + 0.5
  Mat4 projection;
  int width = 0;
  int height = 0;
  // Also rasterize the back-face layer (GBufferImages::back_position).
  bool back_layer = false;
  // Also GBufferImages::back_albedo; needs back_layer.
  bool back_albedo = false;
  // MiB the call may allocate; 0: the default (glint/memory.h, TraceOptions).
  double memory_limit_mb = 0.0;
};

struct GBufferImages {
  Image position;  // (x, y, z, 1) where a triangle covers the pixel centre, 0 elsewhere
  Image normal;    // unit view-space normal (flipped toward the eye on back faces), w = 1
  Image specular;  // (specular rgb, shininess_to_alpha(shininess))
  // With RasterInputs::back_layer: the nearest back-facing surface strictly
  // behind the front one, (x, y, z, 1), 0 where there is none. A closed
  // object's far side, so back - front is its thickness along the view ray.
  Image back_position;
  // With RasterInputs::back_albedo: (albedo r, g, b of the back-layer
  // triangle's material, 1) exactly where back_position is set, 0 elsewhere.
  // A reflected ray that meets an object's hidden side is shaded with that
  // side's own material, which the front layer cannot tell.
  Image back_albedo;
};

// Throws InvalidArgument naming the bad field (sizes, material indices,
// material values, back_albedo without back_layer).
void validate(const RasterInputs& in);

}  // namespace glint
