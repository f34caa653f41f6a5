// The OpenGL backend: every stage as a fragment pass over a full-screen
// triangle (the rasterizer as one MRT pass over the mesh), on an EGL context
// that lives on one worker thread owned by this file.
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
#include "gl/gl_backend.h"
#include "cpu/march.h"
#include "gl/program.h"
#include "glint/backend.h"
#include "glint/errors.h"
#include "glint/marches.h"

namespace glint {
namespace gl {
namespace {

std::string mib(double bytes) {
  char buf[32];
  const double m = bytes / (1024.0 * 1024.0);
  std::snprintf(buf, sizeof buf, m < 10.0 ? "%.1f" : "%.0f", m);
  return buf;
}

std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

double rgba32f_bytes(int w, int h) { return static_cast<double>(w) * h * 16.0; }

// --------------------------------------------------------------------------
// State that lives on the worker thread: the context and every GL object.

class GlState {
 public:
  struct Texture {
    GLuint id = 0;
    int w = 0, h = 0;
  };
  explicit GlState(const std::string& egl_library) : ctx_(egl_library), gl_(ctx_.api()) {
    gl_.GenVertexArrays(1, &empty_vao_);
    gl_.GenFramebuffers(1, &fbo_);
    check("creating the framebuffer");
  }

  ~GlState() {
    for (auto& kv : programs_) gl_.DeleteProgram(kv.second);
    for (Texture& t : textures_) release(t);
    if (pyramid_.id) gl_.DeleteTextures(1, &pyramid_.id);
    release_raster();
    gl_.DeleteFramebuffers(1, &fbo_);
    gl_.DeleteVertexArrays(1, &empty_vao_);
    gl_.Finish();
  }

  const ContextInfo& info() const { return ctx_.info(); }
  const Api& api() const { return gl_; }

  Image trace(const TraceInputs& in, const TraceOptions& opt) {
    const int w = in.position.width, h = in.position.height;
    const int passes_textures = in.specular ? 4 : 3;
    const Texture& pos = upload(kIn0, in.position, "trace", passes_textures);
    const Texture& nrm = upload(kIn1, in.normal, "trace", passes_textures);
    const Texture* spec = in.specular ? &upload(kIn2, *in.specular, "trace", passes_textures) : nullptr;
    const MarchInfo& info = march_info(opt.march);
    const Texture* back = in.back_position && info.uses_back_position
                              ? &upload(kAux, *in.back_position, "trace", passes_textures + 1)
                              : nullptr;
    if (info.id == March::Hiz) build_pyramid(in, opt, pos, nrm, back);
    const GLuint prog = program(info.gl_program);
    gl_.UseProgram(prog);
    bind(prog, "u_position", 0, pos, GL_NEAREST, GL_CLAMP_TO_EDGE);
    bind(prog, "u_normal", 1, nrm, GL_NEAREST, GL_CLAMP_TO_EDGE);
    // An unused sampler still needs a complete texture bound; reuse the normal one.
    bind(prog, "u_specular", 2, spec ? *spec : nrm, GL_NEAREST, GL_CLAMP_TO_EDGE);
    gl_.Uniform1i(loc(prog, "u_has_specular"), spec ? 1 : 0);
    float pf[16];
    for (int i = 0; i < 16; ++i) pf[i] = static_cast<float>(in.projection.m[i]);
    gl_.Uniform1fv(loc(prog, "u_proj"), 16, pf);
    gl_.Uniform1dv(loc(prog, "u_projd"), 16, in.projection.m.data());
    gl_.Uniform1i(loc(prog, "u_kind"), static_cast<int>(classify_projection(in.projection)));
    cpu::MarchSetup::Eye eye_kind;
    float eye[3];
    cpu::camera_eye(in.projection, eye_kind, eye);
    gl_.Uniform1i(loc(prog, "u_eye_kind"), static_cast<int>(eye_kind));
    gl_.Uniform3f(loc(prog, "u_eye"), eye[0], eye[1], eye[2]);
    gl_.Uniform2f(loc(prog, "u_size"), static_cast<float>(w), static_cast<float>(h));
    gl_.Uniform1f(loc(prog, "u_max_distance"), opt.max_distance);
    gl_.Uniform1f(loc(prog, "u_thickness"), opt.thickness);
    gl_.Uniform1i(loc(prog, "u_steps"), opt.steps);
    const float r = opt.resolution;
    gl_.Uniform1f(loc(prog, "u_resolution"), r < 0.0f ? 0.0f : (r > 1.0f ? 1.0f : r));
    if (info.id == March::Hiz) {
      bind_hiz_inputs(prog, in, pos, back);
      gl_.ActiveTexture(GL_TEXTURE0 + 4);
      gl_.BindTexture(GL_TEXTURE_2D, pyramid_.id);
      gl_.Uniform1i(loc(prog, "u_pyramid"), 4);
      gl_.Uniform1i(loc(prog, "u_levels"), pyramid_.levels);
    }
    return draw_and_read(w, h, info.name, passes_textures);
  }

  // The Hi-Z pyramid of march_hiz (native/src/cpu/march_hiz.cpp): level 0
  // from the G-buffer, then each level from the one below, all on the GPU.
  // Each reduction reads level L - 1 as the texture's only visible level
  // while rendering into level L, so no pass samples what it writes.
  void build_pyramid(const TraceInputs& in, const TraceOptions& opt, const Texture& pos,
                     const Texture& nrm, const Texture* back) {
    const int w = in.position.width, h = in.position.height;
    pyramid_target(w, h);
    const GLuint base = program("hiz_base.frag");
    gl_.UseProgram(base);
    bind(base, "u_position", 0, pos, GL_NEAREST, GL_CLAMP_TO_EDGE);
    bind(base, "u_normal", 1, nrm, GL_NEAREST, GL_CLAMP_TO_EDGE);
    bind_hiz_inputs(base, in, pos, back);
    gl_.Uniform2f(loc(base, "u_size"), static_cast<float>(w), static_cast<float>(h));
    gl_.Uniform1f(loc(base, "u_thickness"), opt.thickness);
    attach_level(pyramid_.id, 0);
    draw(w, h);
    const GLuint reduce = program("hiz_reduce.frag");
    gl_.UseProgram(reduce);
    gl_.Uniform1i(loc(reduce, "u_src"), 5);
    int sw = w, sh = h;
    for (int level = 1; level < pyramid_.levels; ++level) {
      const int dw = std::max(1, sw / 2), dh = std::max(1, sh / 2);
      gl_.ActiveTexture(GL_TEXTURE0 + 5);
      gl_.BindTexture(GL_TEXTURE_2D, pyramid_.id);
      gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, level - 1);
      gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, level - 1);
      gl_.Uniform4i(loc(reduce, "u_sizes"), sw, sh, dw, dh);
      attach_level(pyramid_.id, level);
      draw(dw, dh);
      sw = dw;
      sh = dh;
    }
    gl_.ActiveTexture(GL_TEXTURE0 + 5);
    gl_.BindTexture(GL_TEXTURE_2D, pyramid_.id);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, 0);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, pyramid_.levels - 1);
    gl_.BindTexture(GL_TEXTURE_2D, 0);
    debug_check("hiz pyramid");
  }

  // The uniforms hiz_common.glsl declares.
  void bind_hiz_inputs(GLuint prog, const TraceInputs& in, const Texture& pos, const Texture* back) {
    const Mat4 inv = inverse(in.projection);
    float f[16];
    for (int k = 0; k < 16; ++k) f[k] = static_cast<float>(inv.m[k]);
    gl_.Uniform1fv(loc(prog, "u_inv"), 16, f);
    // An unused sampler still needs a complete texture: the position stands in.
    bind(prog, "u_back", 3, back ? *back : pos, GL_NEAREST, GL_CLAMP_TO_EDGE);
    gl_.Uniform1i(loc(prog, "u_has_back"), back ? 1 : 0);
  }

  // An RG32F texture with every mip level down to 1x1, kept between frames.
  void pyramid_target(int w, int h) {
    if (pyramid_.id && pyramid_.w == w && pyramid_.h == h) return;
    if (pyramid_.id) gl_.DeleteTextures(1, &pyramid_.id);
    pyramid_ = Pyramid{};
    int levels = 1;
    for (int lw = w, lh = h; lw > 1 || lh > 1; ++levels) {
      lw = std::max(1, lw / 2);
      lh = std::max(1, lh / 2);
    }
    check_size(w, h, "the hiz pyramid", 1);
    while (gl_.GetError() != GL_NO_ERROR) {
    }
    gl_.GenTextures(1, &pyramid_.id);
    scratch_unit();
    gl_.BindTexture(GL_TEXTURE_2D, pyramid_.id);
    gl_.TexStorage2D(GL_TEXTURE_2D, levels, GL_RG32F, w, h);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST_MIPMAP_NEAREST);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    const GLenum err = gl_.GetError();
    if (err != GL_NO_ERROR) {
      gl_.DeleteTextures(1, &pyramid_.id);
      pyramid_ = Pyramid{};
      if (err == GL_OUT_OF_MEMORY) out_of_memory(w, h, "the hiz pyramid", 1);
      throw Error(std::string("glint GL: allocating the hiz pyramid failed: ") + gl_error_name(err));
    }
    pyramid_.w = w;
    pyramid_.h = h;
    pyramid_.levels = levels;
  }

  void attach_level(GLuint tex, int level) {
    gl_.BindFramebuffer(GL_FRAMEBUFFER, fbo_);
    gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, level);
    const GLenum buf = GL_COLOR_ATTACHMENT0;
    gl_.DrawBuffers(1, &buf);
    if (gl_.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw Error("glint GL: level " + std::to_string(level) + " of the hiz pyramid cannot be rendered to on " +
                  info().renderer);
  }

  Image reflection_color(const Image& uv, const Image& color) {
    const Texture& t_uv = upload(kIn0, uv, "reflection_color", 3);
    // GL_LINEAR would blend a NaN or Inf texel into its neighbours; the CPU
    // reads such texels as black, so they are zeroed (in a copy, and only
    // when there are any).
    const Image* src = &color;
    Image clean;
    if (!std::all_of(color.data.begin(), color.data.end(), [](float v) { return std::isfinite(v); })) {
      clean = color;
      for (float& v : clean.data)
        if (!std::isfinite(v)) v = 0.0f;
      src = &clean;
    }
    const Texture& t_color = upload(kIn1, *src, "reflection_color", 3);
    const GLuint prog = program("reflection_color.frag");
    gl_.UseProgram(prog);
    bind(prog, "u_uv", 0, t_uv, GL_NEAREST, GL_CLAMP_TO_EDGE);
    bind(prog, "u_color", 1, t_color, GL_LINEAR, GL_CLAMP_TO_EDGE);
    return draw_and_read(uv.width, uv.height, "reflection_color", 3);
  }

  Image box_blur(const Image& src, const BlurOptions& opt, const int* region) {
    const int w = src.width, h = src.height;
    if (opt.size == 0) return src;
    int x0 = 0, y0 = 0, x1 = w, y1 = h;
    if (region) {
      x0 = std::max(0, region[0]);
      y0 = std::max(0, region[1]);
      x1 = std::min(w, region[2]);
      y1 = std::min(h, region[3]);
    }
    if (x0 >= x1 || y0 >= y1) return src;
    const float sep = std::max(opt.separation, 1.0f);
    const int reach = static_cast<int>(std::ceil(opt.size * sep)) + 1;
    const int hy0 = std::max(0, y0 - reach), hy1 = std::min(h, y1 + reach);

    const Texture& t_src = upload(kIn0, src, "box_blur", 3);
    const Texture& t_horiz = target(kAux, w, h, "box_blur", 3);
    const GLuint prog = program("box_blur.frag");
    gl_.UseProgram(prog);
    gl_.Uniform1i(loc(prog, "u_size"), opt.size);
    gl_.Uniform1f(loc(prog, "u_separation"), sep);
    gl_.Uniform1f(loc(prog, "u_norm"),
                  1.0f / static_cast<float>((2 * opt.size + 1) * (2 * opt.size + 1)));
    gl_.Uniform4i(loc(prog, "u_region"), x0, y0, x1, y1);

    // Pass 0: horizontal sums, only where pass 1 will read them.
    bind(prog, "u_src", 0, t_src, GL_NEAREST, GL_CLAMP_TO_EDGE);
    bind(prog, "u_horiz", 1, t_src, GL_NEAREST, GL_CLAMP_TO_EDGE);  // unused in pass 0
    gl_.Uniform1i(loc(prog, "u_pass"), 0);
    attach(t_horiz);
    gl_.Enable(GL_SCISSOR_TEST);
    gl_.Scissor(x0, hy0, x1 - x0, hy1 - hy0);
    draw(w, h);
    gl_.Disable(GL_SCISSOR_TEST);
    debug_check("box_blur (horizontal pass)");

    // Pass 1: vertical sums inside the region, a copy of the source outside.
    bind(prog, "u_horiz", 1, t_horiz, GL_NEAREST, GL_CLAMP_TO_EDGE);
    gl_.Uniform1i(loc(prog, "u_pass"), 1);
    return draw_and_read(w, h, "box_blur (vertical pass)", 3);
  }

  Image reflection(const Image& color, const Image& blurred, const Image& specular) {
    const Texture& c = upload(kIn0, color, "reflection", 4);
    const Texture& b = upload(kIn1, blurred, "reflection", 4);
    const Texture& s = upload(kIn2, specular, "reflection", 4);
    const GLuint prog = program("reflection.frag");
    gl_.UseProgram(prog);
    bind(prog, "u_color", 0, c, GL_NEAREST, GL_CLAMP_TO_EDGE);
    bind(prog, "u_blurred", 1, b, GL_NEAREST, GL_CLAMP_TO_EDGE);
    bind(prog, "u_specular", 2, s, GL_NEAREST, GL_CLAMP_TO_EDGE);
    return draw_and_read(color.width, color.height, "reflection", 4);
  }

  Image combine(const Image& base, const Image& refl, Combine mode) {
    const Texture& b = upload(kIn0, base, "combine", 3);
    const Texture& r = upload(kIn1, refl, "combine", 3);
    const GLuint prog = program("combine.frag");
    gl_.UseProgram(prog);
    bind(prog, "u_base", 0, b, GL_NEAREST, GL_CLAMP_TO_EDGE);
    bind(prog, "u_reflection", 1, r, GL_NEAREST, GL_CLAMP_TO_EDGE);
    gl_.Uniform1i(loc(prog, "u_mode"), mode == Combine::Over ? 0 : 1);
    return draw_and_read(base.width, base.height, "combine", 3);
  }

  GBufferImages rasterize(const RasterInputs& in);

  void compile_for_test(const std::string& entry) {
    std::vector<std::string> stages;
    if (entry.size() > 5 && entry.compare(entry.size() - 5, 5, ".frag") == 0)
      stages.push_back("fullscreen.vert");
    stages.push_back(entry);
    gl_.DeleteProgram(link_program(gl_, stages));
  }

 private:
  // Textures are kept between calls and reallocated only when the size
  // changes, so a sequence of frames allocates once. Every pass uses the
  // same few slots, so a large frame's memory is given back as soon as a
  // smaller one runs.
  enum Slot { kIn0, kIn1, kIn2, kOut, kAux, kSlots };

  void release(Texture& t) {
    if (t.id) gl_.DeleteTextures(1, &t.id);
    t = Texture{};
  }

  // Drains the GL error queue; throws on the first error with `what`.
  void check(const std::string& what) {
    const GLenum first = gl_.GetError();
    if (first == GL_NO_ERROR) return;
    for (int i = 0; i < 16 && gl_.GetError() != GL_NO_ERROR; ++i) {
    }
    throw Error(std::string("glint GL: ") + gl_error_name(first) + " after " + what + " on " +
                info().renderer);
  }

  // After every pass in debug builds; release builds skip the round trip.
  void debug_check(const std::string& what) {
#ifndef NDEBUG
    check(what);
#else
    (void)what;
#endif
  }

  // The texture limits, before any allocation: an 8K frame on a GL whose
  // limit is 4K fails here, with the numbers, instead of inside the driver.
  void check_size(int w, int h, const char* pass, int textures) {
    const ContextInfo& ci = info();
    const int max_w = std::min(ci.max_texture_size, ci.max_viewport[0]);
    const int max_h = std::min(ci.max_texture_size, ci.max_viewport[1]);
    if (w > max_w || h > max_h)
      throw Error("glint GL: " + size_text(w, h) + " is larger than this OpenGL allows (" +
                  size_text(max_w, max_h) + ": GL_MAX_TEXTURE_SIZE " +
                  std::to_string(ci.max_texture_size) + ", GL_MAX_VIEWPORT_DIMS " +
                  size_text(ci.max_viewport[0], ci.max_viewport[1]) + " on " + ci.renderer +
                  "); " + pass + " needs " + std::to_string(textures) + " RGBA32F textures of " +
                  mib(rgba32f_bytes(w, h)) + " MiB each. Use backend=\"cpu\" for this size.");
  }

  [[noreturn]] void out_of_memory(int w, int h, const char* pass, int textures) {
    throw Error("glint GL: out of memory: " + size_text(w, h) + " RGBA32F needs " +
                mib(rgba32f_bytes(w, h)) + " MiB per texture, " + mib(rgba32f_bytes(w, h) * textures) +
                " MiB for the " + std::to_string(textures) + " textures of " + pass + " (GL_OUT_OF_MEMORY on " +
                info().renderer + "). Use a smaller image or backend=\"cpu\".");
  }

  // A w x h RGBA32F texture in `slot`, allocated if its size changed.
  // Allocation errors are checked in every build: running out of memory is
  // an expected outcome for large frames, not a bug.
  Texture& target(Slot slot, int w, int h, const char* pass, int textures) {
    Texture& t = textures_[slot];
    if (t.id && t.w == w && t.h == h) return t;
    release(t);
    check_size(w, h, pass, textures);
    while (gl_.GetError() != GL_NO_ERROR) {
    }
    gl_.GenTextures(1, &t.id);
    scratch_unit();
    gl_.BindTexture(GL_TEXTURE_2D, t.id);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
    gl_.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, nullptr);
    const GLenum err = gl_.GetError();
    if (err != GL_NO_ERROR) {
      release(t);
      if (err == GL_OUT_OF_MEMORY) out_of_memory(w, h, pass, textures);
      throw Error(std::string("glint GL: allocating a ") + size_text(w, h) + " RGBA32F texture for " +
                  pass + " failed: " + gl_error_name(err));
    }
    t.w = w;
    t.h = h;
    return t;
  }

  Texture& upload(Slot slot, const Image& img, const char* pass, int textures) {
    Texture& t = target(slot, img.width, img.height, pass, textures);
    scratch_unit();
    gl_.BindTexture(GL_TEXTURE_2D, t.id);
    gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
    gl_.TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, img.width, img.height, GL_RGBA, GL_FLOAT,
                      img.data.data());
    const GLenum err = gl_.GetError();
    if (err == GL_OUT_OF_MEMORY) out_of_memory(img.width, img.height, pass, textures);
    if (err != GL_NO_ERROR)
      throw Error(std::string("glint GL: uploading a texture for ") + pass + " failed: " +
                  gl_error_name(err));
    return t;
  }

  // Binding a texture to work on it replaces what the active unit held, and
  // the passes' inputs sit on units 0..3: uploads and allocations use a unit
  // no pass samples from.
  void scratch_unit() { gl_.ActiveTexture(GL_TEXTURE0 + 15); }

  GLint loc(GLuint prog, const char* name) { return gl_.GetUniformLocation(prog, name); }

  void bind(GLuint prog, const char* sampler, int unit, const Texture& t, GLint filter, GLint wrap) {
    gl_.ActiveTexture(GL_TEXTURE0 + unit);
    gl_.BindTexture(GL_TEXTURE_2D, t.id);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, wrap);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, wrap);
    gl_.Uniform1i(loc(prog, sampler), unit);
  }

  // `vert` + `frag`, compiled on first use and kept (every fragment shader
  // is used with one vertex shader only).
  GLuint program(const std::string& frag, const char* vert = "fullscreen.vert") {
    auto it = programs_.find(frag);
    if (it != programs_.end()) return it->second;
    const GLuint p = link_program(gl_, {vert, frag});
    programs_[frag] = p;
    return p;
  }

  void attach(const Texture& t) {
    gl_.BindFramebuffer(GL_FRAMEBUFFER, fbo_);
    gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, t.id, 0);
    const GLenum buf = GL_COLOR_ATTACHMENT0;
    gl_.DrawBuffers(1, &buf);
    const GLenum status = gl_.CheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
      throw Error("glint GL: the RGBA32F render target is incomplete (status 0x" +
                  [&] {
                    char b[16];
                    std::snprintf(b, sizeof b, "%x", status);
                    return std::string(b);
                  }() +
                  ") on " + info().renderer);
  }

  void draw(int w, int h) {
    gl_.Viewport(0, 0, w, h);
    gl_.BindVertexArray(empty_vao_);
    gl_.DrawArrays(GL_TRIANGLES, 0, 3);
  }

  // Reads the colour attachment `attachment` of the bound framebuffer.
  Image read(int w, int h, GLenum attachment, const char* pass) {
    Image out;
    try {
      out = Image(w, h);
    } catch (const std::bad_alloc&) {
      throw Error("glint GL: out of host memory: " + size_text(w, h) + " RGBA32F needs " +
                  mib(rgba32f_bytes(w, h)) + " MiB for the result of " + pass);
    }
    gl_.ReadBuffer(attachment);
    gl_.PixelStorei(GL_PACK_ALIGNMENT, 4);
    gl_.ReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, out.data.data());
    const GLenum err = gl_.GetError();
    if (err == GL_OUT_OF_MEMORY) out_of_memory(w, h, pass, 1);
    if (err != GL_NO_ERROR)
      throw Error(std::string("glint GL: ") + gl_error_name(err) + " in " + pass + " on " +
                  info().renderer);
    return out;
  }

  Image draw_and_read(int w, int h, const char* pass, int textures) {
    const Texture& out = target(kOut, w, h, pass, textures);
    attach(out);
    draw(w, h);
    debug_check(pass);
    return read(w, h, GL_COLOR_ATTACHMENT0, pass);
  }

  // --- rasterizer objects, kept between frames like the textures -----------
  struct RasterTargets {
    GLuint fbo = 0, depth = 0, color[3] = {0, 0, 0};
    int w = 0, h = 0;
  };
  RasterTargets raster_;
  GLuint raster_vao_ = 0;
  GLuint buffers_[6] = {0, 0, 0, 0, 0, 0};  // positions, normals, uvs, tangents, triangle material, material table
  std::vector<GLuint> normal_map_textures_;

  void release_raster_targets() {
    if (raster_.fbo) gl_.DeleteFramebuffers(1, &raster_.fbo);
    if (raster_.depth) gl_.DeleteRenderbuffers(1, &raster_.depth);
    for (GLuint& c : raster_.color)
      if (c) gl_.DeleteTextures(1, &c);
    raster_ = RasterTargets{};
  }

  void release_raster() {
    release_raster_targets();
    if (back_.fbo) gl_.DeleteFramebuffers(1, &back_.fbo);
    if (back_.depth) gl_.DeleteRenderbuffers(1, &back_.depth);
    if (back_.color) gl_.DeleteTextures(1, &back_.color);
    back_ = BackTargets{};
    if (raster_vao_) gl_.DeleteVertexArrays(1, &raster_vao_);
    raster_vao_ = 0;
    for (GLuint& b : buffers_)
      if (b) gl_.DeleteBuffers(1, &b);
    std::fill(std::begin(buffers_), std::end(buffers_), 0u);
    if (!normal_map_textures_.empty())
      gl_.DeleteTextures(static_cast<GLsizei>(normal_map_textures_.size()), normal_map_textures_.data());
    normal_map_textures_.clear();
  }

  void raster_targets(int w, int h);
  Image rasterize_back(int w, int h, size_t tris, double base, double depth_scale, const float* proj);
  struct BackTargets {
    GLuint fbo = 0, depth = 0, color = 0;
    int w = 0, h = 0;
  };
  BackTargets back_;
  void buffer_data(int index, GLenum target, size_t bytes, const void* data, const char* what);

  EglContext ctx_;
  const Api& gl_;
  GLuint empty_vao_ = 0;
  GLuint fbo_ = 0;
  Texture textures_[kSlots];
  struct Pyramid {
    GLuint id = 0;
    int w = 0, h = 0, levels = 0;
  };
  Pyramid pyramid_;
  std::map<std::string, GLuint> programs_;
};

void GlState::raster_targets(int w, int h) {
  if (raster_.fbo && raster_.w == w && raster_.h == h) return;
  release_raster_targets();
  const ContextInfo& ci = info();
  if (w > ci.max_renderbuffer_size || h > ci.max_renderbuffer_size) {
    throw Error("glint GL: " + size_text(w, h) + " is larger than this OpenGL's depth buffers allow (" +
                "GL_MAX_RENDERBUFFER_SIZE " + std::to_string(ci.max_renderbuffer_size) + " on " +
                ci.renderer + "). Use backend=\"cpu\" for this size.");
  }
  check_size(w, h, "rasterize", 4);
  while (gl_.GetError() != GL_NO_ERROR) {
  }
  gl_.GenFramebuffers(1, &raster_.fbo);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, raster_.fbo);
  gl_.GenTextures(3, raster_.color);
  scratch_unit();
  for (int i = 0; i < 3; ++i) {
    gl_.BindTexture(GL_TEXTURE_2D, raster_.color[i]);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl_.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, nullptr);
    gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + i, GL_TEXTURE_2D,
                             raster_.color[i], 0);
  }
  gl_.GenRenderbuffers(1, &raster_.depth);
  gl_.BindRenderbuffer(GL_RENDERBUFFER, raster_.depth);
  gl_.RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
  gl_.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, raster_.depth);
  const GLenum err = gl_.GetError();
  if (err != GL_NO_ERROR) {
    raster_.w = raster_.h = 0;
    if (err == GL_OUT_OF_MEMORY) out_of_memory(w, h, "rasterize", 4);
    throw Error(std::string("glint GL: allocating the G-buffer targets failed: ") + gl_error_name(err));
  }
  const GLenum status = gl_.CheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw Error("glint GL: the G-buffer framebuffer (3 x RGBA32F + DEPTH32F) is incomplete on " +
                ci.renderer);
  raster_.w = w;
  raster_.h = h;
}

void GlState::buffer_data(int index, GLenum target, size_t bytes, const void* data, const char* what) {
  if (!buffers_[index]) gl_.GenBuffers(1, &buffers_[index]);
  gl_.BindBuffer(target, buffers_[index]);
  while (gl_.GetError() != GL_NO_ERROR) {
  }
  // Never a zero-sized store (some drivers reject binding one): tiny data is
  // padded in a copy, since GL reads the whole size from `data`.
  unsigned char padded[16] = {};
  if (bytes < sizeof padded) {
    if (bytes) std::memcpy(padded, data, bytes);
    data = padded;
    bytes = sizeof padded;
  }
  gl_.BufferData(target, static_cast<GLsizeiptr>(bytes), data, GL_STREAM_DRAW);
  const GLenum err = gl_.GetError();
  if (err == GL_OUT_OF_MEMORY)
    throw Error("glint GL: out of memory: the " + std::string(what) + " buffer needs " + mib(double(bytes)) +
                " MiB (GL_OUT_OF_MEMORY on " + info().renderer + ")");
  if (err != GL_NO_ERROR)
    throw Error(std::string("glint GL: uploading the ") + what + " buffer failed: " + gl_error_name(err));
}

GBufferImages GlState::rasterize(const RasterInputs& in) {
  const int w = in.width, h = in.height;
  const Mesh& mesh = in.mesh;
  const size_t tris = mesh.triangle_count();
  raster_targets(w, h);

  // Triangles with a non-finite corner are skipped, as on the CPU: they are
  // collapsed to a point (zero area covers nothing). Corner normals that are
  // non-finite or all zero give the face normal everywhere on the CPU, so
  // they are replaced by it here. Both only copy when there is such a triangle.
  const std::vector<float>* positions = &mesh.positions;
  const std::vector<float>* normals = &mesh.normals;
  std::vector<float> pos_copy, nrm_copy;
  double d_min = 0.0, d_max = 0.0;
  bool any_vertex = false;
  for (size_t t = 0; t < tris; ++t) {
    const float* p = mesh.positions.data() + t * 9;
    bool finite = true;
    for (int k = 0; k < 9; ++k) finite = finite && std::isfinite(p[k]);
    if (!finite) {
      if (pos_copy.empty()) pos_copy = mesh.positions;
      std::fill(pos_copy.begin() + t * 9, pos_copy.begin() + t * 9 + 9, 0.0f);
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      const double d = -static_cast<double>(p[3 * k + 2]);
      if (!any_vertex || d < d_min) d_min = d;
      if (!any_vertex || d > d_max) d_max = d;
      any_vertex = true;
    }
    const float* n = mesh.normals.data() + t * 9;
    bool n_finite = true, n_zero = true;
    for (int k = 0; k < 9; ++k) {
      n_finite = n_finite && std::isfinite(n[k]);
      n_zero = n_zero && n[k] == 0.0f;
    }
    if (!n_finite || n_zero) {
      if (nrm_copy.empty()) nrm_copy = mesh.normals;
      const double e1[3] = {double(p[3]) - p[0], double(p[4]) - p[1], double(p[5]) - p[2]};
      const double e2[3] = {double(p[6]) - p[0], double(p[7]) - p[1], double(p[8]) - p[2]};
      const double c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                           e1[0] * e2[1] - e1[1] * e2[0]};
      const double len = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
      for (int k = 0; k < 3; ++k)
        for (int a = 0; a < 3; ++a)
          nrm_copy[t * 9 + 3 * k + a] = len > 1e-30 ? static_cast<float>(c[a] / len) : 0.0f;
    }
  }
  if (!pos_copy.empty()) positions = &pos_copy;
  if (!nrm_copy.empty()) normals = &nrm_copy;

  // The depth test compares view distances, as the CPU does. A float depth
  // buffer still only takes [0, 1], so the distance is offset and scaled by
  // a power of two: the scaling is exact, and with no offset (all of a
  // perspective camera's visible points lie in front of it) the comparison
  // keeps every bit of the distance.
  // A lower bound of the visible view distances: the near plane for a
  // perspective (> 0) or orthographic camera, else the nearest corner.
  const ProjectionKind kind = classify_projection(in.projection);
  double lower = d_min;
  if (kind == ProjectionKind::Perspective) {
    lower = 0.0;
  } else if (kind == ProjectionKind::Orthographic) {
    // clip z = -1 on the near plane
    lower = std::max(d_min, (1.0 + in.projection(2, 3)) / in.projection(2, 2));
  }
  // Rounded down a little so that float rounding of the base cannot push a
  // visible distance below it (it would be clamped to 0 and tie).
  const double base = lower >= 0.0 ? 0.0 : lower - std::fabs(lower) * 1e-5 - 1e-30;
  int exponent = 0;
  std::frexp(std::max(d_max - base, 1e-30), &exponent);
  const double depth_scale = std::ldexp(1.0, -(exponent + 1));  // (d - base) * scale < 0.5

  // --- buffers ---------------------------------------------------------------
  // uvs and tangents are only bound when they are there for every triangle
  // (validate() guarantees it wherever a triangle's material has a map).
  bool any_map = tris > 0 && mesh.uvs.size() == tris * 6 && mesh.tangents.size() == tris * 12;
  bool map_used = false;
  for (const Material& m : in.materials) map_used = map_used || m.normal_map >= 0;
  any_map = any_map && map_used;
  buffer_data(0, GL_ARRAY_BUFFER, positions->size() * sizeof(float), positions->data(), "positions");
  buffer_data(1, GL_ARRAY_BUFFER, normals->size() * sizeof(float), normals->data(), "normals");
  if (any_map) {
    buffer_data(2, GL_ARRAY_BUFFER, mesh.uvs.size() * sizeof(float), mesh.uvs.data(), "uvs");
    buffer_data(3, GL_ARRAY_BUFFER, mesh.tangents.size() * sizeof(float), mesh.tangents.data(),
                "tangents");
  }
  buffer_data(4, GL_SHADER_STORAGE_BUFFER, mesh.material.size() * sizeof(int32_t), mesh.material.data(),
              "material index");
  // Per material: specular rgb and the specular buffer's alpha.
  std::vector<float> table(in.materials.size() * 4);
  for (size_t k = 0; k < in.materials.size(); ++k) {
    const Material& m = in.materials[k];
    table[4 * k + 0] = m.specular[0];
    table[4 * k + 1] = m.specular[1];
    table[4 * k + 2] = m.specular[2];
    table[4 * k + 3] = shininess_to_alpha(m.shininess);
  }
  buffer_data(5, GL_SHADER_STORAGE_BUFFER, table.size() * sizeof(float), table.data(), "material");

  if (!raster_vao_) gl_.GenVertexArrays(1, &raster_vao_);
  gl_.BindVertexArray(raster_vao_);
  gl_.BindBuffer(GL_ARRAY_BUFFER, buffers_[0]);
  gl_.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  gl_.EnableVertexAttribArray(0);
  gl_.BindBuffer(GL_ARRAY_BUFFER, buffers_[1]);
  gl_.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  gl_.EnableVertexAttribArray(1);
  if (any_map) {
    gl_.BindBuffer(GL_ARRAY_BUFFER, buffers_[2]);
    gl_.VertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
    gl_.EnableVertexAttribArray(2);
    gl_.BindBuffer(GL_ARRAY_BUFFER, buffers_[3]);
    gl_.VertexAttribPointer(3, 4, GL_FLOAT, GL_FALSE, 0, nullptr);
    gl_.EnableVertexAttribArray(3);
  } else {
    // A previous frame's arrays may still be enabled, and shorter than this mesh.
    gl_.DisableVertexAttribArray(2);
    gl_.DisableVertexAttribArray(3);
  }
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buffers_[4]);
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, buffers_[5]);

  // Normal maps: one texture each, sampled GL_LINEAR + GL_REPEAT like the
  // CPU's sample_normal_map().
  if (!normal_map_textures_.empty())
    gl_.DeleteTextures(static_cast<GLsizei>(normal_map_textures_.size()), normal_map_textures_.data());
  normal_map_textures_.assign(in.normal_maps.size(), 0);
  if (!normal_map_textures_.empty()) {
    gl_.GenTextures(static_cast<GLsizei>(normal_map_textures_.size()), normal_map_textures_.data());
    scratch_unit();
    for (size_t k = 0; k < in.normal_maps.size(); ++k) {
      const Image& img = in.normal_maps[k];
      check_size(img.width, img.height, "a normal map", 1);
      gl_.BindTexture(GL_TEXTURE_2D, normal_map_textures_[k]);
      gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
      gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
      gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
      gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
      gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
      gl_.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, img.width, img.height, 0, GL_RGBA, GL_FLOAT,
                     img.data.data());
    }
    const GLenum err = gl_.GetError();
    if (err == GL_OUT_OF_MEMORY)
      throw Error("glint GL: out of memory uploading " + std::to_string(in.normal_maps.size()) +
                  " normal maps");
    if (err != GL_NO_ERROR)
      throw Error(std::string("glint GL: uploading the normal maps failed: ") + gl_error_name(err));
  }

  // --- the pass ----------------------------------------------------------------
  const GLuint prog = program("gbuffer.frag", "gbuffer.vert");
  gl_.UseProgram(prog);
  float pf[16];
  for (int i = 0; i < 16; ++i) pf[i] = static_cast<float>(in.projection.m[i]);
  gl_.Uniform1fv(loc(prog, "u_proj"), 16, pf);
  gl_.Uniform1f(loc(prog, "u_depth_base"), static_cast<float>(base));
  gl_.Uniform1f(loc(prog, "u_depth_scale"), static_cast<float>(depth_scale));
  gl_.Uniform1i(loc(prog, "u_normal_map"), 0);

  gl_.BindFramebuffer(GL_FRAMEBUFFER, raster_.fbo);
  const GLenum bufs[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
  gl_.DrawBuffers(3, bufs);
  gl_.Viewport(0, 0, w, h);
  const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  const float one = 1.0f;
  for (int i = 0; i < 3; ++i) gl_.ClearBufferfv(GL_COLOR, i, zero);
  gl_.DepthMask(GL_TRUE);
  gl_.ClearBufferfv(GL_DEPTH, 0, &one);
  gl_.Enable(GL_DEPTH_TEST);
  // Strictly nearer wins, so of two equally near triangles the first one
  // submitted keeps the pixel, as on the CPU.
  gl_.DepthFunc(GL_LESS);

  // One draw per run of consecutive triangles sharing a normal map (usually
  // one per material), in submission order, so depth ties resolve the same.
  size_t first = 0;
  while (first < tris) {
    const int map = in.materials[mesh.material[first]].normal_map;
    size_t last = first + 1;
    while (last < tris && in.materials[mesh.material[last]].normal_map == map) ++last;
    gl_.ActiveTexture(GL_TEXTURE0);
    gl_.BindTexture(GL_TEXTURE_2D, map >= 0 ? normal_map_textures_[map] : 0);
    gl_.Uniform1i(loc(prog, "u_has_normal_map"), map >= 0 ? 1 : 0);
    gl_.Uniform1i(loc(prog, "u_first_triangle"), static_cast<GLint>(first));
    gl_.DrawArrays(GL_TRIANGLES, static_cast<GLint>(first * 3), static_cast<GLsizei>((last - first) * 3));
    first = last;
  }
  gl_.Disable(GL_DEPTH_TEST);
  debug_check("rasterize (G-buffer pass)");

  GBufferImages out;
  out.position = read(w, h, GL_COLOR_ATTACHMENT0, "rasterize");
  out.normal = read(w, h, GL_COLOR_ATTACHMENT1, "rasterize");
  out.specular = read(w, h, GL_COLOR_ATTACHMENT2, "rasterize");
  if (in.back_layer) out.back_position = rasterize_back(w, h, tris, base, depth_scale, pf);
  return out;
}

// The back-face layer: every triangle again into a target of its own, each
// fragment kept only if it is back-facing and behind the front layer's
// surface (read from the front pass's position target, still on the GPU).
Image GlState::rasterize_back(int w, int h, size_t tris, double base, double depth_scale,
                              const float* proj) {
  if (!(back_.fbo && back_.w == w && back_.h == h)) {
    if (back_.fbo) gl_.DeleteFramebuffers(1, &back_.fbo);
    if (back_.depth) gl_.DeleteRenderbuffers(1, &back_.depth);
    if (back_.color) gl_.DeleteTextures(1, &back_.color);
    back_ = BackTargets{};
    while (gl_.GetError() != GL_NO_ERROR) {
    }
    gl_.GenFramebuffers(1, &back_.fbo);
    gl_.BindFramebuffer(GL_FRAMEBUFFER, back_.fbo);
    gl_.GenTextures(1, &back_.color);
    scratch_unit();
    gl_.BindTexture(GL_TEXTURE_2D, back_.color);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
    gl_.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, nullptr);
    gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, back_.color, 0);
    gl_.GenRenderbuffers(1, &back_.depth);
    gl_.BindRenderbuffer(GL_RENDERBUFFER, back_.depth);
    gl_.RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
    gl_.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, back_.depth);
    const GLenum err = gl_.GetError();
    if (err == GL_OUT_OF_MEMORY) out_of_memory(w, h, "the back-face layer", 2);
    if (err != GL_NO_ERROR)
      throw Error(std::string("glint GL: allocating the back-face layer failed: ") + gl_error_name(err));
    back_.w = w;
    back_.h = h;
  }
  const GLuint prog = program("gbuffer_back.frag", "gbuffer.vert");
  gl_.UseProgram(prog);
  gl_.Uniform1fv(loc(prog, "u_proj"), 16, proj);
  gl_.Uniform1f(loc(prog, "u_depth_base"), static_cast<float>(base));
  gl_.Uniform1f(loc(prog, "u_depth_scale"), static_cast<float>(depth_scale));
  gl_.ActiveTexture(GL_TEXTURE0 + 1);
  gl_.BindTexture(GL_TEXTURE_2D, raster_.color[0]);
  gl_.Uniform1i(loc(prog, "u_front"), 1);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, back_.fbo);
  const GLenum buf = GL_COLOR_ATTACHMENT0;
  gl_.DrawBuffers(1, &buf);
  gl_.Viewport(0, 0, w, h);
  const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  const float one = 1.0f;
  gl_.ClearBufferfv(GL_COLOR, 0, zero);
  gl_.DepthMask(GL_TRUE);
  gl_.ClearBufferfv(GL_DEPTH, 0, &one);
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthFunc(GL_LESS);
  gl_.BindVertexArray(raster_vao_);
  gl_.DrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(tris * 3));
  gl_.Disable(GL_DEPTH_TEST);
  debug_check("rasterize (back-face layer)");
  return read(w, h, GL_COLOR_ATTACHMENT0, "rasterize (back-face layer)");
}

// --------------------------------------------------------------------------
// The worker thread that owns the GlState.

class Worker {
 public:
  explicit Worker(const std::string& egl_library) : pid_(getpid()), sync_(std::make_unique<Sync>()) {
    std::exception_ptr failure;
    bool ready = false;
    Sync& sy = *sync_;
    thread_ = std::thread([&, egl_library] {
      try {
        state_ = std::make_unique<GlState>(egl_library);
      } catch (...) {
        failure = std::current_exception();
      }
      {
        std::lock_guard<std::mutex> lock(sy.mu);
        ready = true;
      }
      sy.cv.notify_all();
      if (state_) loop();
    });
    std::unique_lock<std::mutex> lock(sy.mu);
    sy.cv.wait(lock, [&] { return ready; });
    lock.unlock();
    if (failure) {
      thread_.join();
      std::rethrow_exception(failure);
    }
  }

  ~Worker() {
    if (getpid() != pid_) {
      // A forked child: the thread and the context exist only in the parent,
      // and the copied mutexes and condition variable still record its
      // waiter (destroying them would block forever). Nothing here can be
      // freed safely; the child's exit reclaims it.
      (void)state_.release();
      (void)sync_.release();
      thread_.detach();
      return;
    }
    {
      std::lock_guard<std::mutex> lock(sync_->mu);
      stop_ = true;
    }
    sync_->cv.notify_all();
    if (thread_.joinable()) thread_.join();
  }

  // Runs f(state) on the worker thread and waits; exceptions come back here.
  void run(const std::function<void(GlState&)>& f) {
    refuse_after_fork();  // the context's thread does not exist in a forked child
    Sync& sy = *sync_;
    std::lock_guard<std::mutex> call(sy.call_mu);  // one caller at a time
    std::unique_lock<std::mutex> lock(sy.mu);
    task_ = &f;
    error_ = nullptr;
    done_ = false;
    sy.cv.notify_all();
    sy.cv.wait(lock, [&] { return done_; });
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void loop() {
    Sync& sy = *sync_;
    std::unique_lock<std::mutex> lock(sy.mu);
    for (;;) {
      sy.cv.wait(lock, [&] { return stop_ || task_ != nullptr; });
      if (task_) {
        const auto* f = task_;
        lock.unlock();
        std::exception_ptr err;
        try {
          (*f)(*state_);
        } catch (const std::bad_alloc&) {
          err = std::make_exception_ptr(Error("glint GL: out of host memory"));
        } catch (...) {
          err = std::current_exception();
        }
        lock.lock();
        error_ = err;
        task_ = nullptr;
        done_ = true;
        sy.cv.notify_all();
        continue;
      }
      if (stop_) break;
    }
    lock.unlock();
    // GL objects and the context go on the thread they were made on.
    state_.reset();
  }

  struct Sync {
    std::mutex call_mu;  // serializes callers
    std::mutex mu;       // guards the task hand-over below
    std::condition_variable cv;
  };

  pid_t pid_;
  std::unique_ptr<Sync> sync_;  // on the heap so a forked child can abandon it
  std::thread thread_;
  const std::function<void(GlState&)>* task_ = nullptr;
  std::exception_ptr error_;
  bool done_ = false;
  bool stop_ = false;
  std::unique_ptr<GlState> state_;
};

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

  Image reflection(const Image& color, const Image& blurred, const Image& specular) override {
    require_image(color, "reflection_color");
    require_same_size(color, "reflection_color", blurred, "reflection_blur");
    require_same_size(color, "reflection_color", specular, "specular");
    Image out;
    worker_.run([&](GlState& s) { out = s.reflection(color, blurred, specular); });
    return out;
  }

  Image combine(const Image& base, const Image& refl, Combine mode) override {
    require_image(base, "color");
    require_same_size(base, "color", refl, "reflection");
    Image out;
    worker_.run([&](GlState& s) { out = s.combine(base, refl, mode); });
    return out;
  }

  GBufferImages rasterize(const RasterInputs& in) override {
    validate(in);
    GBufferImages out;
    worker_.run([&](GlState& s) { out = s.rasterize(in); });
    return out;
  }

  void compile_for_test(const std::string& entry) {
    worker_.run([&](GlState& s) { s.compile_for_test(entry); });
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
