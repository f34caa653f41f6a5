// What a compositor that samples the reflection colour itself (the Blender
// add-on's node group) needs from one frame's G-buffer, made in one call so
// that the G-buffer crosses into the core once per frame (docs/addon.md).
#pragma once
#include <cstddef>
#include <cstdint>

#include "glint/image.h"
#include "glint/options.h"
#include "glint/stages.h"

namespace glint {

struct CompositeLayers {
  // (u, v, vis, replaced): the trace, with the uv of misses next to hits
  // continued from those hits (continue_missing_uv). `replaced` is the share
  // of the engine's own specular the pixel's reflection replaces: vis, or at
  // a hidden side (below) the hidden image's vis.
  Image uv;
  // rgb: the split-sum weight (Backend::specular_weight), a: the cone blur's
  // level (cone_lod_at) at hits, continued to the misses around them
  // (continue_lod_into_misses); 0 for mirrors and pixels that do not reflect.
  Image weight;
  // Given back_albedo: hidden_sides(). Those pixels' uv has vis 0 (a
  // compositor must not also show the front texel there), their u, v kept
  // (Map UV's derivatives) and their lod a hit's. With the hiz march, also
  // the hidden shares of settle_uncertain_shares(), whose uv keeps its vis.
  // Empty without back_albedo.
  Image hidden;
  // Pixels seen with a positive specular amount: what the trace traced.
  uint64_t reflective_pixels = 0;
  uint64_t hidden_pixels = 0;
  // Some pixel's lod is above 0: a blur has work to do.
  bool any_rough = false;
};

// Rings of pixels with vis = 0 around the hits (vis > 0), one ring per pass,
// get the mean uv of their hit (or earlier-ring) 3x3 neighbours; vis stays
// 0, so they still show nothing. A resampler that estimates each pixel's uv
// derivatives from its neighbours (Blender's Map UV) would otherwise see the
// jump from a hit's uv to a miss's (0, 0) and filter a hit over half the
// frame. Sums in the order dy, dx = -1..1, in float.
void continue_missing_uv(Image& uv, int rings, int threads = 0);

// A glossy reflection is blurred on both sides of its outline, but a miss
// (vis 0) has no cone of its own, so a blur gathered at each pixel's own lod
// would spread a reflection only inward. Each seen, reflective miss takes the
// lod of the hit nearest to it (3x3 chamfer distance) when it lies within
// half that hit's footprint, 2^(lod - 1) pixels (times kChamferSlack, the
// most the chamfer distance overstates a Euclidean one). Hits keep their
// lod; the other pixels that footprints can reach get 0 when they are farther,
// unseen or do not reflect. `weight`'s alpha is the lod; vis is uv's third
// channel.
constexpr float kChamferSlack = 1.0824f;
void continue_lod_into_misses(Image& weight, const Image& uv, const Image& specular, const Image& position,
                              int threads = 0);

// Where the colour stages read a reflection: every reported uv (vis > 0) that
// lies in a texel on an object's outline moves to the centre of the texel one
// step inside the object. The frame blends an outline texel's object with
// what lies behind it (the engine's antialiasing), while a hit there is on
// the object: a sphere's rim seen from above, reflected from below, read as
// rim and floor mixed (grey teeth along the top of its reflection). The
// reflection's own coverage of an outline is the trace's business
// (TraceOptions::antialias). Outline: a 4-neighbour unseen or farther than
// the texel's depth plus its thickness (back_position's, else `thickness`,
// TraceOptions::thickness); inside: the step away from every such neighbour, taken when
// the texel there is seen and no farther than that bound (a texel with such
// neighbours on opposite sides, a line one texel thin, stays). A uv in a
// texel off the outline but within half a texel of one, along an axis, moves
// to its texel's centre on that axis, since the sampler's footprint would
// take in the outline's blend: the texel beside it on that side lies outside
// it, or is itself an outline seen along the line (the next texel lies outside
// that one). The trace's own uv, which accuracy is scored on, is not changed.
void read_inside_outlines(Image& uv, const Image& position, const Image* back_position, float thickness,
                          int threads = 0);

// A ray that blocked="occluder" reports met an object inside its thickness:
// it entered through the side the camera does not see, the back-face layer's
// surface at the occluder's texel. Where that texel has a back surface
// (`back_albedo` alpha > 0, glint::GBufferImages::back_albedo), the pixel
// shows that surface in its material's colour: (albedo, vis), 0 elsewhere
// (a compositor weighs the albedo by vis, as it does what it samples at a hit). Reads the trace's fourth channel (hit visibility, 0 for an
// occluder); `count` gets the number of such pixels. How a compositor lights
// the colour is its choice (docs/addon.md, *Hidden sides*).
Image hidden_sides(const Image& traced_uv, const Image& back_albedo, uint64_t& count, int threads = 0);

// What the hiz march was unsure of, settled from the pixel's neighbours
// (docs/hiz.md, *Uncertain shares inside a reflection*). A hit with
// visibility under its screen-edge fade (an outline texel's confidence: the
// ray may have passed beside the object there) whose eight neighbours all report
// something within hiz::kReusePixels of its hit (a hidden side entered at any
// distance: it reports the texel its ray entered, texels behind the rim) lies
// inside its reflection, so its ray cannot have passed into the open: where a neighbour
// came in by the object's hidden side (and the hit's texel has a back
// surface, or else the texel that neighbour entered), the rest of the fade
// goes to that side, in `hidden` as
// (albedo x share / fade, share): a compositor weighs the hidden colour by the
// pixel's whole replaced share (vis + share = fade), so the albedo is scaled
// to its part; elsewhere the hit takes the whole fade. `uv` is the trace's
// own (its fourth channel tells hits, occluders and hidden sides apart);
// returns the number of pixels given a hidden share. composite_layers() runs
// it for the hiz march when given back_albedo.
uint64_t settle_uncertain_shares(Image& uv, Image& hidden, const Image& back_albedo, int threads = 0);

// A grid of values cut into bins by runs of rows and of columns (row_bin[r],
// col_bin[c]: each bin's index, never decreasing, below bin_rows and
// bin_cols), and per bin the mean of its positive values, 0 where it has none,
// into out[bin_rows * bin_cols]. Value (r, c) is values[r * row_stride + c *
// col_stride] (floats; a channel of an image). The sums run as numpy's
// add.reduceat runs them, down each column of a bin's rows and then across
// its columns, each as the first plus the sum of the rest (numpy's order for
// bins up to 8 rows and columns wide), in float, and the mean is the float of
// the double quotient:
// the add-on's coarse blur levels (addon/glint/logic/compositing.py,
// coarse_images) read the same bits whichever computes them. Throws
// InvalidArgument on bins out of order or range.
void positive_bin_means(const float* values, std::ptrdiff_t row_stride, std::ptrdiff_t col_stride, int rows,
                        int cols, const int* row_bin, const int* col_bin, int bin_rows, int bin_cols, float* out,
                        int threads = 0);

// Where the engine's specular at every texel is W x one colour (a uniform
// world: the add-on's "world colour" path), the colour a hit samples holds
// its own surface's specular as the camera sees it, W(hit) x colour with
// W at the camera's N.V there. The ray that meets it sees that surface from
// elsewhere: along the ray its specular is W'(hit) x colour, W' the same
// split-sum weight at N.V = -ray . normal(hit). So the share of the colour
// a compositor takes out grows by vis x (W(hit) - W'(hit)) (rgb means) x
// (1 - the hit's own vis): where the hit has a reflection of its own, a
// second bounce puts that in, and it keeps the camera's weight:
// `replaced` += vis x k. It can leave [0, 1]; a compositor that subtracts
// replaced x colour before weighting then reflects the hit as the ray sees it
// (docs/look-core.md, *The hit's own specular*). `weight` is
// composite_layers()'s (its alpha already the lod), `uv` its final uv.
void reweight_hit_specular(Image& uv, const Image& weight, const TraceInputs& in, int threads = 0);

// Trace on `backend` (specular given: only reflective pixels are traced),
// then the weight on the same backend and the lod. No trace, weight or lod
// when nothing reflects (all zero, reflective_pixels 0). With back_albedo
// (same size as the position), also the hidden sides (hidden_sides()). With
// world_specular, the hits' own specular is taken along the ray
// (reweight_hit_specular()).
CompositeLayers composite_layers(Backend& backend, const TraceInputs& in, const TraceOptions& opt,
                                 int threads = 0, const Image* back_albedo = nullptr,
                                 bool world_specular = false);

}  // namespace glint
