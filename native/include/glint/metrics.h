// How far a reflected-uv buffer is from the exact one (march="exact"): the
// accuracy contract (docs/conventions.md), in one place for the bindings, the CLI, the
// sweeps and the add-on's "Measure this scene".
#pragma once
#include "glint/image.h"

namespace glint {

struct AccuracyOptions {
  float tolerance_px = 1.5f;   // pixels: a reported uv this close to the exact hit is right
  float report_above = 1e-3f;  // visibility above which a pixel reports a reflection
};

struct Accuracy {
  long long reported = 0;           // pixels whose visibility > report_above
  long long exact_visible = 0;      // pixels the exact march reports
  long long correct = 0;            // reported within tolerance of an exact hit
  long long found = 0;              // exact hits reported within tolerance (== correct)
  long long false_reflections = 0;  // reported where the exact march reports nothing
  double precision = 1.0;           // correct / reported; 1 when nothing is reported
  double recall = 1.0;              // found / exact_visible; 1 when nothing is there to find
  double median_px = 0.0;           // pixel error where both report (0 when none)
  double p95_px = 0.0;
  double max_px = 0.0;
  // Image space: |reflection colour at uv - at the exact uv|, averaged over
  // rgb and over the reflective pixels (specular amount > 0 where a specular
  // buffer is given, else every pixel where either buffer reports). Negative
  // when no colour was given.
  double image_mae = -1.0;
  long long image_pixels = 0;
  // Per pixel: r = false reflection, g = right, b = missed, r+g = reported
  // but more than the tolerance off; alpha 1 where any of these, else 0.
  Image disagreement;
};

// uv and exact are (u, v, visibility, ...) buffers of one size; color and
// specular are optional (nullptr) images of that size too.
Accuracy compare_uv(const Image& uv, const Image& exact, const Image* color, const Image* specular,
                    const AccuracyOptions& opt = {});

}  // namespace glint
