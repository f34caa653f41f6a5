/* A stand-in EGL library for tests/blender: it forwards every call to the
 * system's libEGL.so.1 (linked as its dependency, so the core's dlsym of a
 * core EGL function on this library finds the real one) and can lose the
 * OpenGL context when the test asks (glint_fault_lose_context, through ctypes).
 * The core loads it because GLINT_EGL_LIBRARY names it: nothing of this is in
 * the shipped library or the add-on. docs/hardening.md.
 *
 * A lost context, as far as the core can see it: from then on read-backs
 * return nothing and the next glGetError reports GL_CONTEXT_LOST (0x0507), as
 * a driver reset does to every command of a lost context. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <string.h>

typedef void (*proc)(void);
typedef unsigned int GLenum;
typedef int GLint;
typedef int GLsizei;

#define GL_CONTEXT_LOST 0x0507

static proc (*real_get_proc)(const char*);
static GLenum (*real_get_error)(void);
static void (*real_read_pixels)(GLint, GLint, GLsizei, GLsizei, GLenum, GLenum, void*);
static int lost, pending;

void glint_fault_lose_context(void) { __atomic_store_n(&lost, 1, __ATOMIC_SEQ_CST); }

int glint_fault_context_lost(void) { return __atomic_load_n(&lost, __ATOMIC_SEQ_CST); }

static GLenum fake_get_error(void) {
  if (__atomic_exchange_n(&pending, 0, __ATOMIC_SEQ_CST)) return GL_CONTEXT_LOST;
  return real_get_error();
}

static void fake_read_pixels(GLint x, GLint y, GLsizei w, GLsizei h, GLenum format, GLenum type,
                             void* data) {
  if (__atomic_load_n(&lost, __ATOMIC_SEQ_CST)) {
    __atomic_store_n(&pending, 1, __ATOMIC_SEQ_CST);
    return;
  }
  real_read_pixels(x, y, w, h, format, type, data);
}

proc eglGetProcAddress(const char* name) {
  if (!real_get_proc) {
    void* lib = dlopen("libEGL.so.1", RTLD_NOW | RTLD_LOCAL);
    if (!lib) return 0;
    real_get_proc = (proc(*)(const char*))dlsym(lib, "eglGetProcAddress");
    if (!real_get_proc) return 0;
  }
  proc p = real_get_proc(name);
  if (p && strcmp(name, "glGetError") == 0) {
    real_get_error = (GLenum(*)(void))p;
    return (proc)fake_get_error;
  }
  if (p && strcmp(name, "glReadPixels") == 0) {
    real_read_pixels = (void (*)(GLint, GLint, GLsizei, GLsizei, GLenum, GLenum, void*))p;
    return (proc)fake_read_pixels;
  }
  return p;
}
