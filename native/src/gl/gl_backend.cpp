// The OpenGL backend: every stage as a fragment pass over a full-screen
// triangle (the rasterizer as one MRT pass over the mesh), on an EGL context
// that lives on one worker thread (worker.h). This file holds the Backend
// face of it and the process-wide instance; GlState (gl_state.h) does the GL.
//
// Why a worker thread: a GL context is current on one thread at a time, and
// callers (Python, Blender's render thread, its UI thread) come from any
// thread. Running all GL work on a thread that never changes keeps the
// context current there for its whole life, leaves the callers' threads
// untouched (Blender has its own GL context current on its main thread, and
// eglMakeCurrent there would replace it), and serializes the work.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <functional>
#include <map>
#include <mutex>
#include <new>
#include <string>
#include <thread>
#include <vector>

#include "gl/egl_context.h"
#include "gl/worker.h"
#include "gl/gl_backend.h"
#include "gl/program.h"
#include "glint/backend.h"
#include "glint/errors.h"
#include "glint/marches.h"
#include "glint/memory.h"

namespace glint {
namespace gl {
namespace {


// --------------------------------------------------------------------------

class GlBackend final : public Backend {
 public:
  explicit GlBackend(const std::string& egl_library) : worker_(egl_library) {
    worker_.run([&](GlState& s) {
      const ContextInfo& ci = s.info();
      description_ = ci.platform + ", OpenGL " + ci.gl_version + ", " + ci.renderer;
    });
  }

  std::string name() const override { return "gl"; }
  const std::string& description() const { return description_; }

  Image trace(const TraceInputs& in, const TraceOptions& opt) override {
    require_trace_inputs(in, opt);
    require_trace_memory(in, opt, true);
    // A march with no GPU form runs its CPU reference (marches() says which).
    const MarchInfo& info = march_info(opt.march);
    if (!info.gl_program) return info.cpu(in, opt, 0);
    Image out;
    worker_.run([&](GlState& s) { out = s.trace(in, opt); });
    return out;
  }

  Image reflection_color(const Image& uv, const Image& color) override {
    require_image(uv, "uv");
    require_image(color, "color");
    Image out;
    worker_.run([&](GlState& s) { out = s.reflection_color(uv, color); });
    return out;
  }

  Image box_blur(const Image& src, const BlurOptions& opt, const int* region) override {
    require_image(src, "image");
    validate(opt);
    Image out;
    worker_.run([&](GlState& s) { out = s.box_blur(src, opt, region); });
    return out;
  }

  Image specular_weight(const Image& position, const Image& normal, const Image& specular,
                        const Mat4& projection) override {
    require_specular_weight_inputs(position, normal, specular, projection);
    Image out;
    worker_.run([&](GlState& s) { out = s.specular_weight(position, normal, specular, projection); });
    return out;
  }

  Image cone_blur(const Image& color, const Image& uv, const Image& specular,
                  const MirrorScale* mirror) override {
    require_cone_blur_inputs(color, uv, specular, mirror);
    Image out;
    worker_.run([&](GlState& s) { out = s.cone_blur(color, uv, specular, mirror); });
    return out;
  }

  Image reflection(const Image& color, const Image* blurred, const Image& specular,
                   const Image* weight) override {
    require_reflection_inputs(color, blurred, specular, weight);
    Image out;
    worker_.run([&](GlState& s) { out = s.reflection(color, blurred, specular, weight); });
    return out;
  }

  Image combine(const Image& base, const Image& refl, Combine mode, const Image* specular_base,
                const Image* coverage) override {
    require_combine_inputs(base, refl, mode, specular_base, coverage);
    Image out;
    worker_.run([&](GlState& s) { out = s.combine(base, refl, mode, specular_base, coverage); });
    return out;
  }

  GBufferImages rasterize(const RasterInputs& in) override {
    validate(in);
    require_raster_memory(in, true);
    GBufferImages out;
    worker_.run([&](GlState& s) { out = s.rasterize(in); });
    return out;
  }

  void compile_for_test(const std::string& entry) {
    worker_.run([&](GlState& s) { s.compile_for_test(entry); });
  }

  void compile_source_for_test(const std::string& entry, const std::string& source, FileNameFn file_name) {
    worker_.run([&](GlState& s) { s.compile_source_for_test(entry, source, file_name); });
  }

 private:
  Worker worker_;
  std::string description_;
};

// The process-wide instance. A failure is remembered with the library it was
// for, so "auto" on a machine without EGL does not retry on every frame.
struct Cache {
  std::mutex mu;
  std::shared_ptr<GlBackend> backend;
  std::string failed_library;
  std::string failure;
};

Cache& cache() {
  // Never destroyed as a whole (a function-local static would be): the
  // backend inside is released by the atexit handler below, which runs
  // before Mesa's own exit handlers, registered when it was loaded.
  static Cache* c = new Cache;
  return *c;
}

void release_at_exit() {
  Cache& c = cache();
  std::shared_ptr<GlBackend> b;
  {
    std::lock_guard<std::mutex> lock(c.mu);
    b.swap(c.backend);
  }
  b.reset();  // joins the worker, which frees the GL objects and the context
}

}  // namespace

std::shared_ptr<Backend> create_gl_backend(const std::string& egl_library) {
  refuse_after_fork();
  return std::make_shared<GlBackend>(egl_library);
}

std::string describe(const Backend& b) {
  const auto* g = dynamic_cast<const GlBackend*>(&b);
  return g ? g->description() : b.name();
}

void compile_for_test(Backend& b, const std::string& entry) {
  auto* g = dynamic_cast<GlBackend*>(&b);
  if (!g) throw Error("compile_for_test: not a GL backend");
  g->compile_for_test(entry);
}

void compile_for_test(Backend& b, const std::string& entry, const std::string& source, FileNameFn file_name) {
  auto* g = dynamic_cast<GlBackend*>(&b);
  if (!g) throw Error("compile_for_test: not a GL backend");
  g->compile_source_for_test(entry, source, file_name);
}

}  // namespace gl

std::shared_ptr<Backend> make_gl_backend() {
  gl::Cache& c = gl::cache();
  std::lock_guard<std::mutex> lock(c.mu);
  gl::refuse_after_fork();
  if (c.backend) return c.backend;
  const std::string library = gl::egl_library_path();
  if (!c.failure.empty() && c.failed_library == library) throw BackendUnavailable(c.failure);
  try {
    c.backend = std::make_shared<gl::GlBackend>(library);
  } catch (const BackendUnavailable& e) {
    c.failed_library = library;
    c.failure = e.what();
    throw;
  }
  static bool registered = false;
  if (!registered) {
    std::atexit(gl::release_at_exit);
    registered = true;
  }
  return c.backend;
}

}  // namespace glint
