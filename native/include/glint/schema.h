// The one place where every option of the pipeline and every number the
// backends share is written. Everything else reads it:
//
//   options.h           the option structs' defaults and limits
//   bindings            glint_core's keyword defaults, the option lines of the
//                       docstrings, glint_core.schema()
//   glint-exr --help    the Pipeline options' lines
//   shaders/            `schema.glsl`, written at build time by glint_schema_gen
//   the add-on          addon/glint/logic/schema.py, written by the same tool
//                       (committed; tests/python/test_schema.py checks it)
//
// Changing a value here changes it everywhere after a build (then copy
// build/generated/schema.py over addon/glint/logic/schema.py). Why each value
// is what it is stays here, beside it. docs/architecture.md lists the other
// single sources (the table of marches, the presets).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

namespace glint {

// --- The specular buffer's encoding (docs/conventions.md) ------------------
// Blender Internal's hardness runs 1..511; the book's shininess is hardness / 4,
// so 511 is 127.75, and the buffer's alpha is shininess / 127.75.
constexpr float kMaxShininess = 127.75f;
constexpr float kHardnessPerShininess = 4.0f;
constexpr float kMinHardness = 1.0f;
// The gloss range (docs/conventions.md): alpha above 1 is hardness past 511,
// for Principled roughness below 0.25. A GGX alpha at or below this is written
// as a mirror (alpha 1): its cone stays inside one pixel for hits up to 1000
// pixels away, and the hardness it would need (3.2e7) would put the buffer's
// alpha (62,600) at the edge of what a half-float EXR holds.
constexpr float kMirrorGgxAlpha = 2.5e-4f;

// --- The look (docs/look-core.md) -----------------------------------------
// A GGX cone's tan, 2 alpha / (1 - alpha^2), grows without bound as alpha
// nears 1 (the cone opens to a half-space); past 16 every footprint covers
// the frame anyway, so it is capped there.
constexpr float kMaxConeTan = 16.0f;
// The shape of the weight's Fresnel term: F = F0 + (1 - F0) Fh(V.H), Fh the
// exact Fresnel of a dielectric of this index of refraction, rescaled to run
// from 0 head on to 1 at grazing. It is what Cycles' Principled BSDF reflects
// with at its default Specular 0.5 (IOR 1.5); Schlick's (1 - V.H)^5 is
// 10-20% under it between 45 and 75 degrees, where a floor is mostly seen.
constexpr float kFresnelShapeIor = 1.5f;

// --- The Hi-Z march (docs/marches.md) --------------------------------------
namespace hiz {
// Picking the cell a ray enters: the point a 64th of a pixel past the
// boundary it just crossed, in its direction of travel. Far below anything
// that moves a reported uv, and above float rounding up to 16k pixels.
constexpr float kCellNudge = 1.0f / 64.0f;
// How far, relative to the surface's distance from the camera, the ray must
// be behind a texel's plane to count as having crossed it. Keeps rays that
// run along a surface (a floor's own rays, just above it) from hitting it
// through rounding.
constexpr float kPlaneTolerance = 1e-5f;
// A ray found behind a texel's plane by at most this share of the texel's
// view distance crossed the surface in the previous texel's footprint (each
// texel has its own plane, so the crossing can fall between two of them).
constexpr float kBehindSlack = 1e-3f;
// Visibility: how well a hit is located, times a fade over this share of the
// screen at its edges (Eevee's default edge fading). A hit found on its
// texel's plane, off any outline, has confidence 1; one located only to its
// texel (no usable normal, or a plane seen edge-on) kUncertain. On an outline
// texel, whose plane may extend past the object, confidence falls from 1 on
// the texel's inner half to kUncertain at its edge facing the outline (the
// chance that the object still covers the hit, outline_confidence()).
constexpr float kEdgeFade = 0.075f;
constexpr float kUncertain = 0.5f;
// The fade of a hit at (u, v) reflected at the pixel whose centre is at
// (ou, ov): 0 on the screen's edge the ray is heading for, 1 from kEdgeFade in.
// That edge is the first one the line from the pixel through the hit meets
// beyond the hit. A reflection's neighbouring rays are cut off where they
// cross that edge, so that is where a fade hides a hard line, in a still and
// as things move. An edge the ray runs along or away from cuts the reflection
// only where the frame cuts the reflector and the reflected object already,
// so fading there dimmed true reflections for nothing (an object at the
// frame's side, reflected in the floor under it). A hit on the pixel itself
// (no direction) fades by its nearest edge. docs/hiz.md, *Visibility*.
inline float screen_edge_fade(float ou, float ov, float u, float v) {
  const float du = u - ou, dv = v - ov;
  const float mu = du > 0.0f ? 1.0f - u : u;  // to the edge each axis heads for
  const float mv = dv > 0.0f ? 1.0f - v : v;
  float edge;
  if (du == 0.0f && dv == 0.0f)
    edge = std::min(std::min(u, 1.0f - u), std::min(v, 1.0f - v));
  else  // the edge reached first: mu / |du| against mv / |dv|, without dividing
    edge = mu * std::fabs(dv) <= mv * std::fabs(du) ? mu : mv;
  return std::min(std::max(edge / kEdgeFade, 0.0f), 1.0f);
}
// The same for a hit of pixel (x, y) of a w x h image: what the march puts in
// a report, and what the composite reads back out of it.
inline float pixel_edge_fade(int x, int y, int w, int h, float u, float v) {
  return screen_edge_fade((static_cast<float>(x) + 0.5f) / static_cast<float>(w),
                          (static_cast<float>(y) + 0.5f) / static_cast<float>(h), u, v);
}
// blocked="occluder": the fourth channel (the hit's own visibility) of a ray
// that came into an object by the side the camera does not see (its back
// layer's surface) is this, where an occluder found a texel late has 0
// (docs/hiz.md, *Blocked rays*).
constexpr float kEnteredHidden = -1.0f;
// An occluder's report is a hidden entry when, inside the texel's thickness,
// the ray lies deeper behind the texel's own depth (flat, not along its
// plane) than this share of the thickness.
constexpr float kHiddenShare = 0.5f;
// A ray further from a texel's own depth (in front or behind) than this many
// times the texel's thickness is off the object there: it neither crosses nor
// is inside it, whatever the texel's tangent plane says (at a rounded
// object's outline that plane runs edge-on, spanning metres). A crossing is
// held to the back layer's thickness alone, being behind the plane to the
// guessed one too.
constexpr float kCrossingDepth = 2.0f;
// A texel's footprint range is clamped to its centre +- this share of its
// view distance (plus its thickness): a plane seen edge-on would otherwise
// reach infinity and make every cell above it overlap every ray.
constexpr float kFootprintSpread = 0.5f;
// Reusing a neighbour's ray: the pixels whose hits are shared lie on one
// smooth surface, their normals within ~11 degrees and their view distances
// within 2% of each other, and the hits lie within 3 pixels of each other,
// so that their mean is within 1.5 pixels of each.
constexpr float kReuseCos = 0.98f;
constexpr float kReuseDepth = 0.02f;
constexpr float kReusePixels = 3.0f;
// Hits further apart than kReusePixels, up to this, are shared too when the
// texels under every hit and under their mean lie on one plane (normals
// within kReuseCos, each off the first's plane by at most kReuseDepth of its
// view distance): a mirror stretches what it reflects, and between hits on
// one plane the mean uv is where the pixel's own ray goes, up to the
// projection's curvature. 8 pixels lost a few hits by 1.5-3 px near the
// corridor's horizon; 6 lost none (docs/hiz.md, *Reusing neighbours' rays*).
constexpr float kReuseSpanPixels = 6.0f;
// ... and only when their visibilities lie within this of each other: a step
// in confidence between them is an outline (one hit on an object's rim), which
// the pixel's own ray places better than a mean does.
constexpr float kReuseSpanVisibility = 0.1f;
// Antialiased outlines (docs/hiz.md): a pixel whose hit meets a miss
// beside it on the same surface also traces rays at these offsets from its
// centre, in pixels: the rotated grid (-n, -f), (f, -n), (n, f), (-f, n),
// whose four samples fall in four different rows and columns of a 4x4 grid,
// so a near-horizontal or near-vertical outline is seen at four positions.
constexpr float kAntialiasNear = 0.125f;
constexpr float kAntialiasFar = 0.375f;
// At resolution <= this the march traces every other pixel of every other
// row first and reuses their rays where they agree (hiz_reuses_rays()).
constexpr float kReuseResolution = 0.5f;
}  // namespace hiz

// --- The rasterizer's back-face layer (docs/rasterizer.md) -----------------
// A back face must lie this share of the front's view distance behind it to
// count: coplanar duplicates and the front triangle's own back side do not.
constexpr double kBackSeparation = 1e-6;

namespace schema {

enum class Type { Float, Double, Int, Name };

// A number (or name) the C++ core, the shaders and the add-on all use.
struct Constant {
  const char* name;  // as the shaders (const) and the add-on (module name) spell it
  Type type;
  double value;      // Type::Name: unused
  const char* text;  // Type::Name: the value; otherwise nullptr
  const char* doc;   // one line
};

inline constexpr Constant kConstants[] = {
    {"MAX_SHININESS", Type::Float, kMaxShininess, nullptr,
     "the book's shininess of Blender Internal's largest hardness (511 / 4)"},
    {"HARDNESS_PER_SHININESS", Type::Float, kHardnessPerShininess, nullptr,
     "Blender Internal hardness per unit of the book's shininess"},
    {"MIN_HARDNESS", Type::Float, kMinHardness, nullptr, "Blender Internal's smallest hardness"},
    {"MIRROR_GGX_ALPHA", Type::Float, kMirrorGgxAlpha, nullptr,
     "GGX alpha at or below which a material is written as a mirror (specular alpha 1)"},
    {"MAX_CONE_TAN", Type::Float, kMaxConeTan, nullptr, "cap of a GGX reflection cone's tan"},
    {"FRESNEL_SHAPE_IOR", Type::Float, kFresnelShapeIor, nullptr,
     "index of refraction whose exact dielectric Fresnel shapes the specular weight's rim"},
    {"CELL_NUDGE", Type::Float, hiz::kCellNudge, nullptr,
     "hiz: pixels past a cell boundary where the next cell is looked up"},
    {"PLANE_TOLERANCE", Type::Float, hiz::kPlaneTolerance, nullptr,
     "hiz: share of the view distance a ray must be behind a texel's plane to cross it"},
    {"BEHIND_SLACK", Type::Float, hiz::kBehindSlack, nullptr,
     "hiz: share of the view distance behind a plane that still counts as a hit"},
    {"EDGE_FADE", Type::Float, hiz::kEdgeFade, nullptr,
     "hiz: share of the screen over which visibility fades at its edges"},
    {"UNCERTAIN", Type::Float, hiz::kUncertain, nullptr,
     "hiz: confidence of a hit located only to its texel, or at the outer edge of an outline texel"},
    {"ENTERED_HIDDEN", Type::Float, hiz::kEnteredHidden, nullptr,
     "hiz, blocked='occluder': the hit channel of a ray that came into an object by its hidden side"},
    {"HIDDEN_SHARE", Type::Float, hiz::kHiddenShare, nullptr,
     "hiz: inside a texel's thickness, deeper than this share of it counts as entered from behind"},
    {"CROSSING_DEPTH", Type::Float, hiz::kCrossingDepth, nullptr,
     "hiz: further from a texel's depth than this many thicknesses is off its object"},
    {"FOOTPRINT_SPREAD", Type::Float, hiz::kFootprintSpread, nullptr,
     "hiz: a texel's depth range at most this share of its view distance either way"},
    {"REUSE_COS", Type::Float, hiz::kReuseCos, nullptr,
     "hiz: least cosine between normals of pixels that share a ray"},
    {"REUSE_DEPTH", Type::Float, hiz::kReuseDepth, nullptr,
     "hiz: largest relative view-distance difference of pixels that share a ray"},
    {"REUSE_PIXELS", Type::Float, hiz::kReusePixels, nullptr,
     "hiz: largest distance in pixels between hits that are shared"},
    {"REUSE_SPAN_PIXELS", Type::Float, hiz::kReuseSpanPixels, nullptr,
     "hiz: largest distance in pixels between shared hits whose texels lie on one plane"},
    {"REUSE_SPAN_VISIBILITY", Type::Float, hiz::kReuseSpanVisibility, nullptr,
     "hiz: largest difference of visibility between hits shared across more than REUSE_PIXELS"},
    {"ANTIALIAS_NEAR", Type::Float, hiz::kAntialiasNear, nullptr,
     "hiz: the rotated grid's smaller offset from a pixel's centre, in pixels"},
    {"ANTIALIAS_FAR", Type::Float, hiz::kAntialiasFar, nullptr,
     "hiz: the rotated grid's larger offset from a pixel's centre, in pixels"},
    {"REUSE_RESOLUTION", Type::Float, hiz::kReuseResolution, nullptr,
     "hiz: resolution at or below which rays are reused"},
    {"BACK_SEPARATION", Type::Double, kBackSeparation, nullptr,
     "back-face layer: least share of the front's view distance a back face lies behind it"},
    {"DEFAULT_PRESET", Type::Name, 0.0, "balanced", "the preset a new Blender scene starts with"},
};

// One keyword of glint_core (and flag of glint-exr, spelt with '-').
struct Option {
  const char* name;
  Type type;
  double initial;            // the default, for numbers
  const char* initial_name;  // the default, for names
  double min, max;           // inclusive limits, for numbers
  const char* unit;
  // Type::Name: the accepted names, nullptr-terminated, in the order of the
  // C++ enum's values; nullptr where another table lists them (the marches).
  const char* const* choices;
  const char* doc;  // one line

  constexpr float initial_float() const { return static_cast<float>(initial); }
  constexpr int initial_int() const { return static_cast<int>(initial); }
  // Position of initial_name among the choices: the default enum value.
  constexpr int initial_index() const { return choice_index(initial_name); }
  // -1 when `name` is not among the choices.
  constexpr int choice_index(std::string_view name) const {
    for (int k = 0; choices && choices[k]; ++k)
      if (name == choices[k]) return k;
    return -1;
  }
};

inline constexpr const char* kBlockedNames[] = {"miss", "occluder", nullptr};
inline constexpr const char* kWeightingNames[] = {"physical", "seed", nullptr};
inline constexpr const char* kBlurNames[] = {"cone", "box", nullptr};
inline constexpr const char* kCombineNames[] = {"over", "seed", nullptr};
inline constexpr const char* kBackendNames[] = {"cpu", "gl", "auto", nullptr};

// The trace: the seed chapter's maxDistance, resolution, steps, thickness.
inline constexpr Option max_distance{"max_distance", Type::Float, 15.0, nullptr, 0.0, 1e12, "view units",
                                     nullptr, "longest reflected ray (past 1e12 float32 positions carry no digits)"};
inline constexpr Option resolution{"resolution", Type::Float, 0.3, nullptr, 0.0, 1.0, "share", nullptr,
                                   "share of the pixels a ray crosses that the coarse pass visits"};
inline constexpr Option steps{"steps", Type::Int, 10, nullptr, 0, 1000000, "iterations", nullptr,
                              "iteration budget; what it counts depends on the march (the table of marches)"};
inline constexpr Option thickness{"thickness", Type::Float, 0.5, nullptr, 0.0, 1e30, "view units", nullptr,
                                  "how far behind a surface still counts as a hit"};
inline constexpr Option march{"march", Type::Name, 0, "seed", 0, 0, "", nullptr,
                              "how rays are marched: a name from the table of marches"};
// Samples a hiz pixel adds where its hit meets a miss beside it (docs/hiz.md,
// *Antialiased outlines*): 0 is one ray per pixel, 4 the rotated grid.
inline constexpr Option antialias{"antialias", Type::Int, 0, nullptr, 0, 4, "rays per pixel", nullptr,
                                  "hiz: extra rays inside a pixel on a reflection's outline, 0 = one ray per pixel"};
inline constexpr Option blocked{"blocked", Type::Name, 0, "miss", 0, 0, "", kBlockedNames,
                                "what a hiz ray blocked by a surface it passes behind reports"};
// The look.
inline constexpr Option weighting{"weighting", Type::Name, 0, "physical", 0, 0, "", kWeightingNames,
                                  "reflection weight: split-sum F0 * A + B, or the seed's mean F0"};
inline constexpr Option blur{"blur", Type::Name, 0, "cone", 0, 0, "", kBlurNames,
                             "rough reflections: per-pixel GGX cone, or the book's fixed box"};
inline constexpr Option blur_size{"blur_size", Type::Int, 8, nullptr, 0, 128, "taps", nullptr,
                                  "box half-width: (2 size + 1)^2 taps, 0 = no blur"};
inline constexpr Option blur_separation{"blur_separation", Type::Float, 1.0, nullptr, 1.0, 64.0, "pixels",
                                        nullptr, "pixels between box taps (the book clamps it to >= 1)"};
inline constexpr Option combine{"combine", Type::Name, 0, "over", 0, 0, "", kCombineNames,
                                "reflection over the base once, or the demo's mix (visibility twice)"};
// Where it runs.
inline constexpr Option backend{"backend", Type::Name, 0, "cpu", 0, 0, "", kBackendNames,
                                "cpu, gl (headless EGL) or auto (gl when a context can be made)"};
inline constexpr Option threads{"threads", Type::Int, 0, nullptr, 0, 1024, "threads", nullptr,
                                "CPU worker threads, 0 = one per hardware thread"};
inline constexpr Option memory_limit_mb{"memory_limit_mb", Type::Double, 0.0, nullptr, 0.0, 1e300, "MiB",
                                        nullptr, "what one call may allocate, 0 = GLINT_MEMORY_LIMIT_MB or half "
                                                 "of physical memory"};

// Every option, in the order help texts list them.
inline constexpr const Option* kOptions[] = {
    &max_distance, &resolution, &steps,    &thickness, &march,   &antialias,       &blocked, &weighting,
    &blur,         &blur_size,  &blur_separation, &combine,   &backend, &threads, &memory_limit_mb};

// A named option's default must be one of its names: checked as the header
// compiles. On the arrays themselves, not through Option::choices: GCC's
// -fsanitize=undefined makes comparing an array's address with nullptr
// (choice_index's test) not a constant expression (scripts/test_sanitized.sh).
namespace detail {
template <std::size_t N>
constexpr bool names_hold(const char* const (&names)[N], std::string_view name) {
  for (std::size_t k = 0; k + 1 < N; ++k)
    if (name == names[k]) return true;
  return false;
}
}  // namespace detail
static_assert(detail::names_hold(kBlockedNames, blocked.initial_name) &&
                  detail::names_hold(kWeightingNames, weighting.initial_name) &&
                  detail::names_hold(kBlurNames, blur.initial_name) &&
                  detail::names_hold(kCombineNames, combine.initial_name) &&
                  detail::names_hold(kBackendNames, backend.initial_name),
              "a named option's default is not among its choices");

// The shortest decimal text that reads back as the same value of `type`
// (15 -> "15.0", 0.3f -> "0.3"), valid in C++, GLSL and Python alike.
inline std::string number_text(double value, Type type) {
  char buf[40];
  if (type == Type::Int) {
    std::snprintf(buf, sizeof buf, "%lld", static_cast<long long>(value));
    return buf;
  }
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, value);
    const bool same = type == Type::Float ? std::strtof(buf, nullptr) == static_cast<float>(value)
                                          : std::strtod(buf, nullptr) == value;
    if (same) break;
  }
  std::string s = buf;
  if (s.find_first_of(".eEin") == std::string::npos) s += ".0";
  return s;
}

// The default as text: a number as number_text() writes it, or the name.
inline std::string initial_text(const Option& o) {
  return o.type == Type::Name ? std::string(o.initial_name) : number_text(o.initial, o.type);
}

}  // namespace schema
}  // namespace glint
