#include "glint/backend.h"

#include <map>
#include <mutex>

#include "glint/errors.h"
#include "glint/options.h"

namespace glint {

bool gl_compiled_in() {
#ifdef GLINT_HAVE_GL
  return true;
#else
  return false;
#endif
}

std::shared_ptr<Backend> get_backend(const std::string& name, int threads) {
  validate_threads(threads);  // here, where every caller passes through
  if (name == "cpu") {
    // The CPU backend is stateless apart from its thread count: cache one per count.
    static std::mutex mu;
    static std::map<int, std::shared_ptr<Backend>> cache;
    std::lock_guard<std::mutex> lock(mu);
    auto& slot = cache[threads];
    if (!slot) slot = make_cpu_backend(threads);
    return slot;
  }
  if (name == "gl") {
#ifdef GLINT_HAVE_GL
    return make_gl_backend();
#else
    throw BackendUnavailable(
        "backend \"gl\": this build of Glint has no OpenGL backend (configured with "
        "GLINT_WITH_GL=OFF)");
#endif
  }
  if (name == "auto") {
#ifdef GLINT_HAVE_GL
    try {
      return make_gl_backend();
    } catch (const BackendUnavailable&) {
      // fall through to the CPU reference
    }
#endif
    return get_backend("cpu", threads);
  }
  throw InvalidArgument("backend", "expected \"cpu\", \"gl\" or \"auto\", got \"" + name + "\"");
}

}  // namespace glint
