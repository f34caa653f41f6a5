#include "gl/egl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <dlfcn.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <vector>

#include "glint/errors.h"

namespace glint::gl {
namespace {

const char* egl_error_name(EGLint e) {
  switch (e) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
    default: return "unknown EGL error";
  }
}

bool has_extension(const char* list, const char* name) {
  if (!list) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    const bool starts = p == list || p[-1] == ' ';
    const bool ends = p[n] == '\0' || p[n] == ' ';
    if (starts && ends) return true;
  }
  return false;
}

constexpr int kRequiredMajor = 4;
constexpr int kRequiredMinor = 3;

}  // namespace

// The EGL entry points, from the dlopen()ed library.
struct EglState {
  void* lib = nullptr;
  PFNEGLGETPROCADDRESSPROC GetProcAddress = nullptr;
  PFNEGLGETERRORPROC GetError = nullptr;
  PFNEGLQUERYSTRINGPROC QueryString = nullptr;
  PFNEGLINITIALIZEPROC Initialize = nullptr;
  PFNEGLBINDAPIPROC BindAPI = nullptr;
  PFNEGLCHOOSECONFIGPROC ChooseConfig = nullptr;
  PFNEGLCREATECONTEXTPROC CreateContext = nullptr;
  PFNEGLDESTROYCONTEXTPROC DestroyContext = nullptr;
  PFNEGLMAKECURRENTPROC MakeCurrent = nullptr;
  PFNEGLCREATEPBUFFERSURFACEPROC CreatePbufferSurface = nullptr;
  PFNEGLDESTROYSURFACEPROC DestroySurface = nullptr;
  PFNEGLRELEASETHREADPROC ReleaseThread = nullptr;
  PFNEGLGETPLATFORMDISPLAYEXTPROC GetPlatformDisplayEXT = nullptr;
  PFNEGLQUERYDEVICESEXTPROC QueryDevicesEXT = nullptr;
  PFNEGLQUERYDEVICESTRINGEXTPROC QueryDeviceStringEXT = nullptr;

  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  EGLSurface surface = EGL_NO_SURFACE;

  const char* error() const { return egl_error_name(GetError()); }
};

namespace {
// The process that loaded EGL, 0 before any attempt.
std::atomic<pid_t> g_egl_pid{0};
}  // namespace

void refuse_after_fork() {
  const pid_t owner = g_egl_pid.load();
  if (owner != 0 && owner != getpid())
    throw BackendUnavailable(
        "OpenGL backend unavailable: this process was forked from one that had already "
        "loaded EGL (pid " + std::to_string(owner) + "); a driver does not survive a fork, so "
        "the GL backend cannot run here. Use backend=\"cpu\", or start the process fresh "
        "(Python multiprocessing: the \"spawn\" start method)");
}

std::string egl_library_path() {
  const char* env = std::getenv("GLINT_EGL_LIBRARY");
  if (env && *env) return env;
  return "libEGL.so.1";
}

const char* gl_error_name(unsigned int code) {
  switch (code) {
    case GL_NO_ERROR: return "GL_NO_ERROR";
    case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
    case GL_STACK_UNDERFLOW: return "GL_STACK_UNDERFLOW";
    case GL_STACK_OVERFLOW: return "GL_STACK_OVERFLOW";
    // A driver reset or a lost device: what a read-back reports then.
    case GL_CONTEXT_LOST: return "GL_CONTEXT_LOST";
    default: return "unknown GL error";
  }
}

namespace {

const char* const kPrefix = "OpenGL backend unavailable: ";

// One headless display EGL could give: a platform and its native handle.
struct Candidate {
  EGLenum platform;
  void* native;
  std::string label;
};

// dlopen()s `library` and finds every EGL entry point Glint calls.
// RTLD_LOCAL: EGL's symbols stay out of the global namespace, where they
// could clash with a host application's own GL (Blender links libGL).
void load_egl(EglState& e, const std::string& library) {
  const std::string prefix = kPrefix;
  refuse_after_fork();
  e.lib = dlopen(library.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (e.lib) g_egl_pid.store(getpid());
  if (!e.lib) {
    const char* why = dlerror();
    throw BackendUnavailable(prefix + "cannot load the EGL library \"" + library + "\" (" +
                             (why ? why : "unknown dlopen error") +
                             "). Install libegl1 and a Mesa or GPU driver (Debian: libegl1 "
                             "libegl-mesa0), or set GLINT_EGL_LIBRARY to the library's path.");
  }
  auto core = [&](const char* name) -> void* {
    void* f = dlsym(e.lib, name);
    if (!f && e.GetProcAddress) f = reinterpret_cast<void*>(e.GetProcAddress(name));
    if (!f)
      throw BackendUnavailable(prefix + "the EGL library \"" + library + "\" has no " + name +
                               " (not an EGL 1.4+ implementation?)");
    return f;
  };
  e.GetProcAddress = reinterpret_cast<PFNEGLGETPROCADDRESSPROC>(core("eglGetProcAddress"));
  e.GetError = reinterpret_cast<PFNEGLGETERRORPROC>(core("eglGetError"));
  e.QueryString = reinterpret_cast<PFNEGLQUERYSTRINGPROC>(core("eglQueryString"));
  e.Initialize = reinterpret_cast<PFNEGLINITIALIZEPROC>(core("eglInitialize"));
  e.BindAPI = reinterpret_cast<PFNEGLBINDAPIPROC>(core("eglBindAPI"));
  e.ChooseConfig = reinterpret_cast<PFNEGLCHOOSECONFIGPROC>(core("eglChooseConfig"));
  e.CreateContext = reinterpret_cast<PFNEGLCREATECONTEXTPROC>(core("eglCreateContext"));
  e.DestroyContext = reinterpret_cast<PFNEGLDESTROYCONTEXTPROC>(core("eglDestroyContext"));
  e.MakeCurrent = reinterpret_cast<PFNEGLMAKECURRENTPROC>(core("eglMakeCurrent"));
  e.CreatePbufferSurface =
      reinterpret_cast<PFNEGLCREATEPBUFFERSURFACEPROC>(core("eglCreatePbufferSurface"));
  e.DestroySurface = reinterpret_cast<PFNEGLDESTROYSURFACEPROC>(core("eglDestroySurface"));
  e.ReleaseThread = reinterpret_cast<PFNEGLRELEASETHREADPROC>(core("eglReleaseThread"));
  e.GetPlatformDisplayEXT = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      e.GetProcAddress("eglGetPlatformDisplayEXT"));
  e.QueryDevicesEXT =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(e.GetProcAddress("eglQueryDevicesEXT"));
  e.QueryDeviceStringEXT = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
      e.GetProcAddress("eglQueryDeviceStringEXT"));
}

// The displays to try, best first: a hardware EGL device (a GPU driver's),
// then Mesa's surfaceless platform, then a software EGL device. The last two
// are both llvmpipe on Mesa, and surfaceless is the better-trodden path
// there. What this EGL cannot offer is noted in `tried`.
std::vector<Candidate> candidate_displays(const EglState& e, std::vector<std::string>& tried) {
  const char* client_ext = e.QueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  std::vector<Candidate> hardware, software, surfaceless;
  if (!e.GetPlatformDisplayEXT || !has_extension(client_ext, "EGL_EXT_platform_base")) {
    tried.push_back("no EGL_EXT_platform_base, so no headless platform can be named");
    return {};
  }
  if (has_extension(client_ext, "EGL_EXT_platform_device") && e.QueryDevicesEXT) {
    EGLint count = 0;
    std::vector<EGLDeviceEXT> devices(16);
    if (e.QueryDevicesEXT(static_cast<EGLint>(devices.size()), devices.data(), &count) && count > 0) {
      for (EGLint i = 0; i < count; ++i) {
        const char* dext =
            e.QueryDeviceStringEXT ? e.QueryDeviceStringEXT(devices[i], EGL_EXTENSIONS) : nullptr;
        const bool soft = has_extension(dext, "EGL_MESA_device_software");
        std::string label = "EGL device " + std::to_string(i) + (soft ? " (software)" : "");
        (soft ? software : hardware).push_back({EGL_PLATFORM_DEVICE_EXT, devices[i], label});
      }
    } else {
      tried.push_back("EGL device platform: no devices");
    }
  } else {
    tried.push_back("EGL device platform: not supported by this EGL");
  }
  if (has_extension(client_ext, "EGL_MESA_platform_surfaceless")) {
    surfaceless.push_back({EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, "EGL surfaceless (Mesa)"});
  } else {
    tried.push_back("EGL surfaceless platform: not supported by this EGL");
  }
  std::vector<Candidate> order = hardware;
  order.insert(order.end(), surfaceless.begin(), surfaceless.end());
  order.insert(order.end(), software.begin(), software.end());
  return order;
}

std::string required_version() {
  return "OpenGL " + std::to_string(kRequiredMajor) + "." + std::to_string(kRequiredMinor) + " core is needed, ";
}

// Why a display refused the 4.3 core context, with what a default context
// of this driver offers when it makes one.
std::string refused_context_reason(const EglState& e, EGLDisplay dpy, EGLConfig config) {
  const std::string why = e.error();
  std::string found;
  EGLContext probe = e.CreateContext(dpy, config, EGL_NO_CONTEXT, nullptr);
  if (probe != EGL_NO_CONTEXT) {
    if (e.MakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, probe)) {
      auto get_string = reinterpret_cast<PFNGLGETSTRINGPROC>(e.GetProcAddress("glGetString"));
      const GLubyte* v = get_string ? get_string(GL_VERSION) : nullptr;
      if (v) found = reinterpret_cast<const char*>(v);
      e.MakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    e.DestroyContext(dpy, probe);
  }
  return required_version() +
         (found.empty() ? "the driver refused it (" + why + ")" : "the driver offers OpenGL " + found);
}

// Every GL entry point into `api`; the name of the first one the driver
// lacks (a broken or partial driver), "" when all are there.
std::string load_gl_functions(const EglState& e, Api& api) {
  std::string missing;
#define GLINT_GL_LOAD(type, name)                                        \
  api.name = reinterpret_cast<type>(e.GetProcAddress("gl" #name));      \
  if (!api.name && missing.empty()) missing = "gl" #name;
  GLINT_GL_FUNCTIONS(GLINT_GL_LOAD)
#undef GLINT_GL_LOAD
  return missing;
}

// What an attempt on `dpy` made, released; not the display itself, for the
// reason given in ~EglContext.
void release_attempt(EglState& e, EGLDisplay dpy) {
  e.MakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  if (e.surface != EGL_NO_SURFACE) e.DestroySurface(dpy, e.surface);
  if (e.context != EGL_NO_CONTEXT) e.DestroyContext(dpy, e.context);
  e.surface = EGL_NO_SURFACE;
  e.context = EGL_NO_CONTEXT;
}

// A 4.3 core context on `c`, made current with the GL loaded into `api`:
// "" on success, else why not. `too_old` gets the first "GL too old" reason.
std::string open_context(EglState& e, const Candidate& c, Api& api, ContextInfo& info, std::string& too_old) {
  EGLDisplay dpy = e.GetPlatformDisplayEXT(c.platform, c.native, nullptr);
  if (dpy == EGL_NO_DISPLAY) return "no display (" + std::string(e.error()) + ")";
  EGLint major = 0, minor = 0;
  if (!e.Initialize(dpy, &major, &minor)) return "eglInitialize failed (" + std::string(e.error()) + ")";
  auto give_up = [&](const std::string& why) {
    release_attempt(e, dpy);
    return why;
  };
  const char* dext = e.QueryString(dpy, EGL_EXTENSIONS);
  if (!e.BindAPI(EGL_OPENGL_API)) return give_up("no desktop OpenGL API (" + std::string(e.error()) + ")");
  const bool surfaceless_ok = has_extension(dext, "EGL_KHR_surfaceless_context");
  EGLConfig config = nullptr;  // EGL_NO_CONFIG_KHR
  if (!surfaceless_ok || !has_extension(dext, "EGL_KHR_no_config_context")) {
    const EGLint want[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLint n = 0;
    if (!e.ChooseConfig(dpy, want, &config, 1, &n) || n < 1) return give_up("no EGL config for OpenGL");
  }
  const EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION, kRequiredMajor,
                             EGL_CONTEXT_MINOR_VERSION, kRequiredMinor,
                             EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                             EGL_NONE};
  e.context = e.CreateContext(dpy, config, EGL_NO_CONTEXT, ctx_attr);
  if (e.context == EGL_NO_CONTEXT) {
    const std::string msg = refused_context_reason(e, dpy, config);
    if (too_old.empty()) too_old = c.label + ": " + msg;
    return give_up(msg);
  }
  if (!surfaceless_ok) {
    const EGLint pb[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
    e.surface = e.CreatePbufferSurface(dpy, config, pb);
    if (e.surface == EGL_NO_SURFACE) return give_up("no pbuffer surface (" + std::string(e.error()) + ")");
  }
  if (!e.MakeCurrent(dpy, e.surface, e.surface, e.context))
    return give_up("eglMakeCurrent failed (" + std::string(e.error()) + ")");
  const std::string missing = load_gl_functions(e, api);
  if (!missing.empty()) return give_up("the driver has no " + missing);
  GLint gl_major = 0, gl_minor = 0;
  api.GetIntegerv(GL_MAJOR_VERSION, &gl_major);
  api.GetIntegerv(GL_MINOR_VERSION, &gl_minor);
  const GLubyte* version = api.GetString(GL_VERSION);
  const GLubyte* renderer = api.GetString(GL_RENDERER);
  info.gl_version = version ? reinterpret_cast<const char*>(version) : "?";
  info.renderer = renderer ? reinterpret_cast<const char*>(renderer) : "?";
  if (gl_major < kRequiredMajor || (gl_major == kRequiredMajor && gl_minor < kRequiredMinor)) {
    const std::string msg = required_version() + "the driver gave " + info.gl_version + " (" + info.renderer + ")";
    if (too_old.empty()) too_old = c.label + ": " + msg;
    return give_up(msg);
  }
  api.GetIntegerv(GL_MAX_TEXTURE_SIZE, &info.max_texture_size);
  api.GetIntegerv(GL_MAX_VIEWPORT_DIMS, info.max_viewport);
  api.GetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &info.max_renderbuffer_size);
  e.display = dpy;
  info.platform = c.label;
  return "";
}

// No display gave a context: the most useful finding first ("GL too old"),
// then everything else that was tried.
BackendUnavailable unavailable(const std::string& library, bool no_candidates, const std::string& too_old,
                               const std::vector<std::string>& tried) {
  std::ostringstream msg;
  msg << kPrefix;
  if (!too_old.empty())
    msg << too_old;
  else if (no_candidates)
    msg << "EGL (\"" << library << "\") offers no headless display";
  else
    msg << "no EGL display gave an OpenGL " << kRequiredMajor << "." << kRequiredMinor << " core context";
  std::vector<std::string> others;
  for (const auto& t : tried)
    if (t != too_old) others.push_back(t);
  if (!others.empty()) {
    msg << ". Also tried: ";
    for (size_t i = 0; i < others.size(); ++i) msg << (i ? "; " : "") << others[i];
  }
  msg << ".";
  return BackendUnavailable(msg.str());
}

}  // namespace

EglContext::EglContext(const std::string& library) : egl_(std::make_unique<EglState>()) {
  info_.egl_library = library;
  load_egl(*egl_, library);
  std::vector<std::string> tried;
  const std::vector<Candidate> order = candidate_displays(*egl_, tried);
  std::string too_old;
  for (const Candidate& c : order) {
    const std::string why = open_context(*egl_, c, api_, info_, too_old);
    if (why.empty()) return;
    tried.push_back(c.label + ": " + why);
  }
  // The library stays loaded: unloading a Mesa that may have started threads
  // during eglInitialize is a known source of crashes at exit.
  throw unavailable(library, order.empty(), too_old, tried);
}

EglContext::~EglContext() {
  EglState& e = *egl_;
  if (e.display == EGL_NO_DISPLAY) return;
  e.MakeCurrent(e.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  if (e.surface != EGL_NO_SURFACE) e.DestroySurface(e.display, e.surface);
  e.DestroyContext(e.display, e.context);
  e.ReleaseThread();
  // No eglTerminate: an EGL display is one per platform and device for the
  // whole process, and something else in it (the host application) may use
  // the same one. No dlclose either: Mesa may still have threads and exit
  // handlers of its own, and unloading it under them crashes at exit.
}

}  // namespace glint::gl
