// glint_core.schema() and the module constants: glint/schema.h as Python sees
// it, for the add-on's generated copy and the test that compares them.
#include <pybind11/pybind11.h>

#include <deque>
#include <string>

#include "bind.h"
#include "glint/options.h"
#include "glint/schema.h"

using namespace pybind11::literals;

namespace glint::py {
namespace {

const char* type_name(schema::Type t) {
  switch (t) {
    case schema::Type::Float: return "float";
    case schema::Type::Double: return "double";
    case schema::Type::Int: return "int";
    case schema::Type::Name: return "name";
  }
  return "?";
}

pyb::object number(double v, schema::Type t) {
  if (t == schema::Type::Int) return pyb::int_(static_cast<long long>(v));
  if (t == schema::Type::Float) return pyb::float_(static_cast<float>(v));
  return pyb::float_(v);
}

pyb::tuple names(const schema::Option& o) {
  pyb::list out;
  for (int k = 0; o.choices && o.choices[k]; ++k) out.append(o.choices[k]);
  return pyb::tuple(out);
}

pyb::dict option_dict(const schema::Option& o) {
  pyb::dict d("type"_a = type_name(o.type), "unit"_a = o.unit, "doc"_a = o.doc);
  if (o.type == schema::Type::Name) {
    d["default"] = o.initial_name;
    d["choices"] = o.choices ? pyb::object(names(o)) : pyb::object(pyb::none());
  } else {
    // The default is a value of the option's type; the limits are compared in
    // double (options.cpp), so they are given as such.
    const schema::Type limits = o.type == schema::Type::Int ? o.type : schema::Type::Double;
    d["default"] = number(o.initial, o.type);
    d["min"] = number(o.min, limits);
    d["max"] = number(o.max, limits);
  }
  return d;
}

pyb::dict py_schema() {
  pyb::dict options, constants;
  for (const schema::Option* o : schema::kOptions) options[o->name] = option_dict(*o);
  for (const schema::Constant& c : schema::kConstants)
    constants[c.name] = c.type == schema::Type::Name ? pyb::object(pyb::str(c.text)) : number(c.value, c.type);
  return pyb::dict("options"_a = options, "constants"_a = constants);
}

std::string range_text(const schema::Option& o) {
  if (o.type == schema::Type::Name) {
    if (!o.choices) return "";
    std::string s;
    for (int k = 0; o.choices[k]; ++k) s += std::string(k ? " | " : "") + "'" + o.choices[k] + "'";
    return s;
  }
  return "[" + schema::number_text(o.min, o.type) + ", " + schema::number_text(o.max, o.type) + "]";
}

}  // namespace

const char* doc_with_options(const char* intro, std::initializer_list<const schema::Option*> options) {
  static std::deque<std::string> keep;  // pybind11 holds on to the pointer
  std::string text = intro;
  text += "\nOptions (glint_core.schema()):";
  for (const schema::Option* o : options) {
    const std::string unit = *o->unit ? std::string(", ") + o->unit : "";
    const std::string range = range_text(*o);
    text += std::string("\n  ") + o->name + " (" + type_name(o->type) + unit + (range.empty() ? "" : ", " + range) +
            ", default " + (o->type == schema::Type::Name ? "'" + schema::initial_text(*o) + "'" : schema::initial_text(*o)) +
            "): " + o->doc;
  }
  keep.push_back(std::move(text));
  return keep.back().c_str();
}

void bind_schema(pyb::module_& m) {
  m.def("schema", &py_schema,
        "{'options': {keyword: {type, unit, default, min, max | choices, doc}}, 'constants': {NAME: value}}:\n"
        "native/include/glint/schema.h, the single source of the options' defaults and limits and of\n"
        "the numbers the backends and the add-on share (addon/glint/logic/schema.py is its copy).");
  m.attr("MAX_SHININESS") = kMaxShininess;
  m.attr("MAX_STEPS") = kMaxSteps;
  m.attr("WEIGHTINGS") = names(schema::weighting);
  m.attr("BLURS") = names(schema::blur);
}

}  // namespace glint::py
