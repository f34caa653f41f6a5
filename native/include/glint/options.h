// The pipeline's options as C++ structs. Their defaults, limits, units and
// names are glint/schema.h's: the seed chapter's trace (maxDistance 15,
// resolution 0.3, steps 10, thickness 0.5) and the book's blur (size 8,
// separation 1: a 17x17 box).
#pragma once
#include <string>

#include "glint/schema.h"

namespace glint {

// The marches; what each is and which options it reads is in glint/marches.h.
// Its names are the table of marches'; schema::march names the default. A
// march's value is its position in native/marches/CMakeLists.txt: these are
// the ones the core itself refers to, and a march added later needs none.
enum class March : int {
  Seed,    // the chapter's two-pass march: coarse pass + bisection
  Linear,  // the book's older single march: fixed view-space steps, step back on a hit
  Hiz,     // min/max depth pyramid walk with ray-span hits
  Exact,   // the mirror ray against the scene's triangles (Embree): the ground truth
};

// The named options' enums list their values in the order of the schema's
// choices (schema::combine, weighting, blur, blocked), which parse_*() and
// to_string() index.
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
// (docs/hiz.md, "Blocked rays").
enum class Blocked {
  Miss,      // nothing: (0, 0, 0, 0), the accuracy contract's answer (default)
  Occluder,  // (u, v, weight, 0) at the occluder: the colour stages show what
             // hides the hit; the 4th channel, the hit's own visibility, says none was found
};

// Each field is the schema's option of the same name (units, limits and
// meaning are there); test_options.cpp checks the march's default by name.
struct TraceOptions {
  float max_distance = schema::max_distance.initial_float();
  float resolution = schema::resolution.initial_float();
  int steps = schema::steps.initial_int();  // its meaning per march is in marches.h
  float thickness = schema::thickness.initial_float();
  March march = March::Seed;
  Blocked blocked = static_cast<Blocked>(schema::blocked.initial_index());  // hiz only
  int antialias = schema::antialias.initial_int();  // hiz only: extra rays on outlines
  // MiB this call (a trace, or the whole pipeline) may allocate (glint/memory.h).
  double memory_limit_mb = schema::memory_limit_mb.initial;
};

struct BlurOptions {
  int size = schema::blur_size.initial_int();                    // keyword blur_size
  float separation = schema::blur_separation.initial_float();   // keyword blur_separation
};

struct PipelineOptions {
  TraceOptions trace;
  BlurOptions blur;
  Combine combine = static_cast<Combine>(schema::combine.initial_index());
  Weighting weighting = static_cast<Weighting>(schema::weighting.initial_index());
  BlurMode blur_mode = static_cast<BlurMode>(schema::blur.initial_index());  // keyword `blur`
  int threads = schema::threads.initial_int();
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
constexpr int kMaxSteps = static_cast<int>(schema::steps.max);
constexpr double kMaxDistanceLimit = schema::max_distance.max;
constexpr int kMaxBlurSize = static_cast<int>(schema::blur_size.max);
constexpr float kMaxBlurSeparation = static_cast<float>(schema::blur_separation.max);
constexpr int kMaxImageSide = 32768;
constexpr int kMaxThreads = static_cast<int>(schema::threads.max);

}  // namespace glint
