// The whole screen-space pipeline in one call, doing only the work the scene
// needs: no trace where nothing is reflective, no blur where nothing is rough.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "glint/stages.h"

namespace glint {

struct PipelineInputs {
  Image position;  // view space (x, y, z, w); w = 1 seen, 0 not
  Image normal;    // view-space normal in xyz
  Image specular;  // rgb specular colour, a = shininess in [0, 1]
  Image color;     // the base image the reflections are taken from and composited over
  Mat4 projection;
  Image back_position;                // optional (empty: none); see TraceInputs
  // Optional (empty: none): the engine's own specular contribution to `color`
  // (rgb), which the reflection replaces where the trace finds a hit
  // (Backend::combine; combine "over" only).
  Image specular_base;
  const TriangleMesh* mesh = nullptr;  // for marches that need the triangles
};

struct StageTiming {
  std::string stage;
  double milliseconds = 0.0;
  bool skipped = false;  // true when the scene did not need the stage
};

struct PipelineResult {
  // Named layers: "uv", "reflection_color", "reflection_blur",
  // "specular_weight", "reflection", "combined". Skipped stages leave zero
  // layers (the blur: the unblurred colour; the weight with weighting "seed").
  std::map<std::string, Image> layers;
  std::vector<StageTiming> timings;
  size_t reflective_pixels = 0;  // pixels with a positive specular amount that were seen
  size_t rough_pixels = 0;       // of those, the ones with roughness > 0
};

PipelineResult run_pipeline(Backend& backend, const PipelineInputs& in, const PipelineOptions& opt);

// Layer names in pipeline order, for the bindings, EXR writer and CLI.
const std::vector<std::string>& pipeline_layer_names();
// Every stage name PipelineResult::timings can hold, in pipeline order (a run
// has one of the two blurs, the one its BlurMode names).
const std::vector<std::string>& pipeline_stage_names();

}  // namespace glint
