// What the binding files share: one bind_*() per area, called by module.cpp,
// and the option lines every docstring takes from glint/schema.h.
#pragma once
#include <pybind11/pybind11.h>

#include <initializer_list>
#include <optional>
#include <string>

#include "glint/image.h"
#include "glint/options.h"
#include "glint/schema.h"

namespace glint::py {

namespace pyb = pybind11;

void bind_schema(pyb::module_& m);    // schema(), MAX_* and the names of the named options
void bind_trace(pyb::module_& m);     // trace, composite_layers, the marches and presets
void bind_pipeline(pyb::module_& m);  // pipeline
void bind_stages(pyb::module_& m);    // each stage on its own
void bind_material(pyb::module_& m);  // the specular buffer's encoding and the look's formulas
void bind_raster(pyb::module_& m);
void bind_exr(pyb::module_& m);
void bind_metrics(pyb::module_& m);
void bind_memory(pyb::module_& m);
void bind_exact(pyb::module_& m);   // ExactScene: the exact march's triangles and BVH kept between frames

// TraceOptions from the keywords trace(), composite_layers() and pipeline()
// share, checked (ValueError naming the keyword).
TraceOptions trace_options(float max_distance, float resolution, int steps, float thickness,
                           const std::string& march, int antialias, const std::string& blocked,
                           double memory_limit_mb);
// An optional image argument: None, or an array of the position buffer's size.
std::optional<Image> optional_image(const pyb::handle& obj, const char* name, const Image& like);

// `intro`, then a line per option (name, type and unit, limits, default,
// meaning) from the schema. The text lives as long as the module: pybind11
// keeps the pointer.
const char* doc_with_options(const char* intro, std::initializer_list<const schema::Option*> options);

}  // namespace glint::py
