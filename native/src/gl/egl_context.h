// A headless OpenGL 4.3 core context from EGL, with no display server and no
// window. libEGL is opened at run time (dlopen) and every GL function comes
// from eglGetProcAddress, so libglint.so loads on machines without any GL and
// a missing piece becomes a BackendUnavailable that names it.
#pragma once
#include <memory>
#include <string>

#include "gl/gl_api.h"

namespace glint::gl {

struct ContextInfo {
  std::string egl_library;  // what was dlopen()ed
  std::string platform;     // "EGL device (...)" or "EGL surfaceless (Mesa)"
  std::string gl_version;   // GL_VERSION
  std::string renderer;     // GL_RENDERER
  int max_texture_size = 0;
  int max_viewport[2] = {0, 0};
  int max_renderbuffer_size = 0;
};

// The EGL library to open: $GLINT_EGL_LIBRARY when set and non-empty (tests
// point it at a missing file to simulate a machine without EGL), else
// "libEGL.so.1" (libglvnd's dispatcher, or a vendor's EGL).
std::string egl_library_path();

struct EglState;  // the dlopen()ed EGL and what it made (egl_context.cpp)

class EglContext {
 public:
  // Opens `library`, finds a display (EGL device platform first, for a GPU,
  // then Mesa's surfaceless platform, then a software device), creates an
  // OpenGL 4.3 core context and makes it current on the calling thread.
  // Throws BackendUnavailable naming what is missing: the library, a
  // display, or the GL version (with the version found).
  explicit EglContext(const std::string& library);
  // Must run on the thread the context is current on.
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  const Api& api() const { return api_; }
  const ContextInfo& info() const { return info_; }

 private:
  std::unique_ptr<EglState> egl_;
  Api api_;
  ContextInfo info_;
};

// Throws BackendUnavailable in a process forked from one that had loaded
// EGL: the driver's state (threads, the display) came across the fork half
// alive, and making a context on it can hang. A child must use the CPU or be
// started fresh (Python multiprocessing: the "spawn" start method).
void refuse_after_fork();

// "GL_INVALID_OPERATION" etc.
const char* gl_error_name(unsigned int code);

}  // namespace glint::gl
