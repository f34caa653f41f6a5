// glint_core: the Python face of the Glint core. Arrays in, arrays out; the
// GIL is released while a stage runs so Blender's UI and other threads go on.
// This file makes the module and its exceptions; each area's functions are
// in a bind_*.cpp of their own (bind.h).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bind.h"
#include "convert.h"
#include "glint/errors.h"
#include "glint/memory.h"
#include "glint/pipeline.h"

namespace glint::py {
namespace {

// Error messages may quote bytes of a file that are not UTF-8 (lenient_str).
void set_python_error(PyObject* type, const char* what) { PyErr_SetObject(type, lenient_str(what).ptr()); }

}  // namespace
}  // namespace glint::py

PYBIND11_MODULE(glint_core, m) {
  using namespace glint;
  using namespace glint::py;
  m.doc() =
      "Glint: screen-space reflections (the seed chapter's pipeline) on numpy arrays.\n"
      "Images are float32 [H, W, C], row 0 at the bottom; view space is Blender's camera space.";

  static pyb::exception<BackendUnavailable> backend_unavailable(m, "BackendUnavailable",
                                                                PyExc_RuntimeError);
  // A MemoryError: code that already handles running out of memory handles a
  // refusal too, and the message says how to raise the limit.
  static pyb::exception<MemoryLimitExceeded> memory_limit_exceeded(m, "MemoryLimitExceeded",
                                                                   PyExc_MemoryError);
  pyb::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InvalidArgument& e) {
      set_python_error(PyExc_ValueError, e.what());
    } catch (const BackendUnavailable& e) {
      set_python_error(backend_unavailable.ptr(), e.what());
    } catch (const MemoryLimitExceeded& e) {
      // Sizes as attributes, so a caller can work out how far to scale down.
      pyb::object exc = pyb::handle(memory_limit_exceeded.ptr())(lenient_str(e.what()));
      exc.attr("needed_bytes") = e.needed_bytes();
      exc.attr("limit_bytes") = e.limit_bytes();
      PyErr_SetObject(memory_limit_exceeded.ptr(), exc.ptr());
    } catch (const pyb::builtin_exception&) {
      throw;  // pybind11's own: its translator knows them
    } catch (const std::runtime_error& e) {
      set_python_error(PyExc_RuntimeError, e.what());
    }
  });

  m.attr("__version__") = "0.1.0";
  m.attr("LAYERS") = pyb::cast(pipeline_layer_names());
  m.attr("STAGES") = pyb::cast(pipeline_stage_names());
  bind_schema(m);
  bind_trace(m);
  bind_pipeline(m);
  bind_stages(m);
  bind_material(m);
  bind_exr(m);
  bind_raster(m);
  bind_metrics(m);
  bind_memory(m);
  bind_exact(m);
}
