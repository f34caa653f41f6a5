// GlState: the context, textures and render targets, uploads and read-backs,
// programs and draws. See gl_state.h.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "gl/gl_state.h"
#include "glint/errors.h"

namespace glint::gl {

GlState::GlState(const std::string& egl_library) : ctx_(egl_library), gl_(ctx_.api()) {
  gl_.GenVertexArrays(1, &empty_vao_);
  gl_.GenFramebuffers(1, &fbo_);
  check("creating the framebuffer");
}

GlState::~GlState() {
  for (auto& kv : programs_) gl_.DeleteProgram(kv.second);
  for (Texture& t : textures_) release(t);
  for (auto& kv : march_objects_) kv.second->release(gl_);
  if (cone_chain_.id) gl_.DeleteTextures(1, &cone_chain_.id);
  release(env_brdf_);
  release_raster();
  gl_.DeleteFramebuffers(1, &fbo_);
  gl_.DeleteVertexArrays(1, &empty_vao_);
  gl_.Finish();
}

void GlState::mip_target(Pyramid& t, int w, int h, GLenum format, const char* stage, int images,
                         const char* name) {
  if (t.id && t.w == w && t.h == h) return;
  if (t.id) gl_.DeleteTextures(1, &t.id);
  t = Pyramid{};
  int levels = 1;
  for (int lw = w, lh = h; lw > 1 || lh > 1; ++levels) {
    lw = std::max(1, lw / 2);
    lh = std::max(1, lh / 2);
  }
  check_size(w, h, stage, images);
  while (gl_.GetError() != GL_NO_ERROR) {
  }
  gl_.GenTextures(1, &t.id);
  scratch_unit();
  gl_.BindTexture(GL_TEXTURE_2D, t.id);
  gl_.TexStorage2D(GL_TEXTURE_2D, levels, format, w, h);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST_MIPMAP_NEAREST);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  const GLenum err = gl_.GetError();
  if (err != GL_NO_ERROR) {
    gl_.DeleteTextures(1, &t.id);
    t = Pyramid{};
    if (err == GL_OUT_OF_MEMORY) out_of_memory(w, h, stage, images);
    throw Error(std::string("glint GL: allocating ") + name + " failed: " + gl_error_name(err));
  }
  t.w = w;
  t.h = h;
  t.levels = levels;
}

void GlState::attach_level(GLuint tex, int level, const Texture* second) {
  gl_.BindFramebuffer(GL_FRAMEBUFFER, fbo_);
  gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, level);
  // Attachment 1 only while a pass writes it: a texture left attached would
  // be a feedback loop for the passes that read it.
  gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, second ? second->id : 0, 0);
  const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  gl_.DrawBuffers(second ? 2 : 1, bufs);
  if (gl_.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw Error("glint GL: level " + std::to_string(level) + " of the hiz pyramid cannot be rendered to on " +
                info().renderer);
}

void GlState::compile_for_test(const std::string& entry) {
  std::vector<std::string> stages;
  if (entry.size() > 5 && entry.compare(entry.size() - 5, 5, ".frag") == 0)
    stages.push_back("fullscreen.vert");
  stages.push_back(entry);
  gl_.DeleteProgram(link_program(gl_, stages));
}

void GlState::compile_source_for_test(const std::string& entry, const std::string& source,
                                      FileNameFn file_name) {
  gl_.DeleteShader(compile_source(gl_, stage_of(entry), source, entry, file_name));
}

void GlState::release(Texture& t) {
  if (t.id) gl_.DeleteTextures(1, &t.id);
  t = Texture{};
}

void GlState::check(const std::string& what) {
  const GLenum first = gl_.GetError();
  if (first == GL_NO_ERROR) return;
  for (int i = 0; i < 16 && gl_.GetError() != GL_NO_ERROR; ++i) {
  }
  throw Error(std::string("glint GL: ") + gl_error_name(first) + " after " + what + " on " +
              info().renderer);
}

void GlState::debug_check(const std::string& what) {
#ifndef NDEBUG
  check(what);
#else
  (void)what;
#endif
}

void GlState::check_size(int w, int h, const char* pass, int textures) {
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

void GlState::out_of_memory(int w, int h, const char* pass, int textures) {
  throw Error("glint GL: out of memory: " + size_text(w, h) + " RGBA32F needs " +
              mib(rgba32f_bytes(w, h)) + " MiB per texture, " + mib(rgba32f_bytes(w, h) * textures) +
              " MiB for the " + std::to_string(textures) + " textures of " + pass + " (GL_OUT_OF_MEMORY on " +
              info().renderer + "). Use a smaller image or backend=\"cpu\".");
}

GlState::Texture& GlState::target(Slot slot, int w, int h, const char* pass, int textures) {
  return target(textures_[slot], w, h, pass, textures);
}

GlState::Texture& GlState::target(Texture& t, int w, int h, const char* pass, int textures) {
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

GlState::Texture& GlState::upload(Slot slot, const Image& img, const char* pass, int textures) {
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

void GlState::bind(GLuint prog, const char* sampler, int unit, const Texture& t, GLint filter, GLint wrap) {
  gl_.ActiveTexture(GL_TEXTURE0 + unit);
  gl_.BindTexture(GL_TEXTURE_2D, t.id);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, wrap);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, wrap);
  gl_.Uniform1i(loc(prog, sampler), unit);
}

GLuint GlState::program(const std::string& frag, const char* vert) {
  auto it = programs_.find(frag);
  if (it != programs_.end()) return it->second;
  const bool compute = frag.size() > 5 && frag.compare(frag.size() - 5, 5, ".comp") == 0;
  const GLuint p = compute ? link_program(gl_, {frag}) : link_program(gl_, {vert, frag});
  programs_[frag] = p;
  return p;
}

void GlState::attach(const Texture& t) {
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

void GlState::draw(int w, int h) {
  gl_.Viewport(0, 0, w, h);
  gl_.BindVertexArray(empty_vao_);
  gl_.DrawArrays(GL_TRIANGLES, 0, 3);
}

void GlState::dispatch(GLuint prog, int w, int h) {
  GLint size[3] = {1, 1, 1};
  gl_.GetProgramiv(prog, GL_COMPUTE_WORK_GROUP_SIZE, size);
  gl_.DispatchCompute(static_cast<GLuint>((w + size[0] - 1) / size[0]),
                      static_cast<GLuint>((h + size[1] - 1) / size[1]), 1);
}

Image GlState::read(int w, int h, GLenum attachment, const char* pass) {
  Image out;
  try {
    out = Image::uninitialized(w, h);  // ReadPixels fills every pixel, or the error below throws
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

Image GlState::draw_and_read(int w, int h, const char* pass, int textures) {
  const Texture& out = target(kOut, w, h, pass, textures);
  attach(out);
  draw(w, h);
  debug_check(pass);
  return read(w, h, GL_COLOR_ATTACHMENT0, pass);
}

}  // namespace glint::gl
