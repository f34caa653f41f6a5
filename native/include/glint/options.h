// Every knob of the pipeline, with units and defaults, in one place.
// Defaults are the seed chapter's (maxDistance 15, resolution 0.3, steps 10,
// thickness 0.5) and the book's blur (size 8, separation 1: a 17x17 box).
#pragma once
#include <string>

namespace glint {

// The marches; what each is and which options it reads is in glint/marches.h.
enum class March {
  Seed,    // the chapter's two-pass march: coarse pass + bisection
  Linear,  // the book's older single march: fixed view-space steps, step back on a hit
  Hiz,     // min/max depth pyramid walk with ray-span hits
  Exact,   // the mirror ray against the scene's triangles (Embree): the ground truth
};

enum class Combine {
  Over,  // base * (1 - reflection.a) + reflection.rgb: visibility applied once (default)
  Seed,  // mix(base, reflection.rgb, reflection.a): the demo's base-combine, visibility twice
};

// How strongly a pixel reflects; the formulas are in docs/look-core.md.
enum class Weighting {
  Physical,  // F0 * A + B, the split-sum environment BRDF at the pixel's N.V and roughness
  Seed,      // the seed's specular amount: mean of the specular rgb (F0), no Fresnel
};

// How rough reflections are blurred; docs/look-core.md.
enum class BlurMode {
  Cone,  // per pixel, a footprint of ray length x GGX cone width, from a mip chain
  Box,   // the book's fixed (2 size + 1)^2 box, mixed in by roughness
};

// What the hiz march reports for a ray that is blocked: one that meets a
// surface inside its thickness, so that what it would hit is hidden behind it
// (docs/marches.md, "Blocked rays").
enum class Blocked {
  Miss,      // nothing: (0, 0, 0, 0), the accuracy contract's answer (default)
  Occluder,  // (u, v, weight, 0) at the occluder: the colour stages show what
             // hides the hit; the 4th channel, the hit's own visibility, says none was found
};

struct TraceOptions {
  float max_distance = 15.0f;  // view-space units (Blender units): longest reflected ray
  float resolution = 0.3f;     // [0, 1]: share of the on-screen pixels the coarse pass visits
  int steps = 10;              // an iteration budget; its meaning per march is in marches.h
  float thickness = 0.5f;      // view-space units: how far behind a surface still counts as a hit
  March march = March::Seed;
  Blocked blocked = Blocked::Miss;  // read by the hiz march only (marches.h)
  // MiB this call (a trace, or the whole pipeline) may allocate; 0: the default,
  // GLINT_MEMORY_LIMIT_MB or a share of physical memory (glint/memory.h).
  double memory_limit_mb = 0.0;
};

struct BlurOptions {
  int size = 8;             // half-width in taps: the box is (2 * size + 1)^2 taps; 0 = no blur
  float separation = 1.0f;  // pixels between taps (>= 1, as the book clamps it)
};

struct PipelineOptions {
  TraceOptions trace;
  BlurOptions blur;
  Combine combine = Combine::Over;
  Weighting weighting = Weighting::Physical;
  BlurMode blur_mode = BlurMode::Cone;  // Python keyword `blur`; BlurOptions apply to Box only
  int threads = 0;  // CPU worker threads; 0 = one per hardware thread
};

// Throw InvalidArgument naming the offending field (Python keyword names).
void validate(const TraceOptions& o);
void validate(const BlurOptions& o);
void validate(const PipelineOptions& o);
// A worker-thread count: 0 (one per hardware thread) to kMaxThreads. Checked
// wherever a count comes in, since a negative one would silently mean "all
// cores" and a huge one start a thread per image row.
void validate_threads(int threads);

// Name <-> enum, for the bindings, the CLI and EXR headers (marches: marches.h).
Combine parse_combine(const std::string& name);  // "over" | "seed"
const char* to_string(Combine c);
Weighting parse_weighting(const std::string& name);  // "physical" | "seed"
const char* to_string(Weighting w);
BlurMode parse_blur_mode(const std::string& name);  // "cone" | "box"
const char* to_string(BlurMode b);
Blocked parse_blocked(const std::string& name);  // "miss" | "occluder"
const char* to_string(Blocked b);

// Limits, public so that docs, bindings and tests quote the same numbers.
constexpr int kMaxSteps = 1000000;
constexpr double kMaxDistanceLimit = 1e12;  // past this float32 view positions carry no digits
constexpr int kMaxBlurSize = 128;
constexpr float kMaxBlurSeparation = 64.0f;
constexpr int kMaxImageSide = 32768;
constexpr int kMaxThreads = 1024;

}  // namespace glint
