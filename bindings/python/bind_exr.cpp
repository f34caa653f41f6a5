// glint_core.read_exr / write_exr: multilayer EXR files as dicts of arrays.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "convert.h"
#include "glint/errors.h"
#include "glint/exr.h"

namespace glint::py {

namespace {

using namespace pybind11::literals;

// str, bytes or any os.PathLike, the way open() takes them.
std::string path_string(const pyb::handle& path) {
  return pyb::module_::import("os").attr("fsdecode")(path).cast<std::string>();
}

pyb::tuple py_read_exr(const pyb::handle& path_obj, double memory_limit_mb) {
  const std::string path = path_string(path_obj);
  ExrFile file;
  {
    pyb::gil_scoped_release release;
    file = read_exr(path, memory_limit_mb);
  }
  pyb::dict layers;
  int width = 0, height = 0;
  // Each array takes its layer's pixels over: nothing is copied.
  while (!file.layers.empty()) {
    auto node = file.layers.extract(file.layers.begin());
    width = node.mapped().width;
    height = node.mapped().height;
    layers[lenient_str(node.key())] = array_from_image(std::move(node.mapped()));
  }
  pyb::dict header;
  header["width"] = width;
  header["height"] = height;
  header["compression"] = lenient_str(file.compression);
  header["options"] = lenient_str(file.options);
  pyb::list skipped;
  for (const std::string& c : file.skipped_channels) skipped.append(lenient_str(c));
  header["skipped_channels"] = skipped;
  if (file.projection) {
    pyb::array_t<double> p({4, 4});
    for (int i = 0; i < 16; ++i) p.mutable_data()[i] = file.projection->m[i];
    header["projection"] = p;
  }
  return pyb::make_tuple(layers, header);
}

void py_write_exr(const pyb::handle& path_obj, const pyb::handle& layers_obj,
                  const pyb::handle& projection, const std::string& options,
                  const std::string& compression) {
  const std::string path = path_string(path_obj);
  if (!pyb::isinstance<pyb::dict>(layers_obj))
    throw InvalidArgument("layers", "expected a dict of name -> float32 [H, W, 3 or 4] array, got " +
                                        pyb::str(pyb::type::of(layers_obj).attr("__name__"))
                                            .cast<std::string>());
  std::map<std::string, Image> layers;
  for (const auto& item : pyb::reinterpret_borrow<pyb::dict>(layers_obj)) {
    if (!pyb::isinstance<pyb::str>(item.first))
      throw InvalidArgument("layers", "expected str keys (layer names), got " +
                                          pyb::repr(item.first).cast<std::string>());
    const std::string name = item.first.cast<std::string>();
    const std::string arg = "layers[\"" + name + "\"]";
    layers[name] = image_from_array(item.second, arg.c_str(), 1.0f, 3);
  }
  ExrWriteOptions opt;
  if (!projection.is_none()) opt.projection = projection_from_array(projection);
  opt.options = options;
  opt.compression = compression;
  pyb::gil_scoped_release release;
  write_exr(path, layers, opt);
}

}  // namespace

void bind_exr(pyb::module_& m) {
  m.def("read_exr", &py_read_exr, "path"_a, pyb::kw_only(), "memory_limit_mb"_a = 0.0,
        "Read a multilayer EXR. Returns (layers, header): layers maps each layer name\n"
        "('position' from position.R/G/B/A or .X/Y/Z/W, 'ViewLayer.Pass' from Blender's\n"
        "names, '' for plain R/G/B/A) to a float32 [H, W, 4] array with row 0 at the\n"
        "BOTTOM; missing R/G/B read 0, a missing A reads 1. header holds width, height,\n"
        "compression, options (the glintOptions string, '' if absent), skipped_channels,\n"
        "and 'projection' (float64 (4, 4), clip = P @ (x, y, z, 1)) when the file has one.\n"
        "A missing or non-EXR file raises ValueError; a corrupt one RuntimeError; one whose\n"
        "layers would take more than memory_limit_mb (0: the default limit) MemoryLimitExceeded.");
  m.def("write_exr", &py_write_exr, "path"_a, "layers"_a, pyb::kw_only(),
        "projection"_a = pyb::none(), "options"_a = "", "compression"_a = "zip",
        "Write a dict of float32 [H, W, 3 or 4] arrays (row 0 at the bottom, all the same\n"
        "size) as a multilayer EXR: layer 'name' becomes FLOAT channels name.R/G/B/A\n"
        "(3-channel arrays get A = 1). projection (4x4) is stored as the m44d attribute\n"
        "glintProjection, options as the string attribute glintOptions. compression:\n"
        "'zip' (default), 'zips', 'piz', 'rle' or 'none' (lossless only).");
}

}  // namespace glint::py
