// GlState: the GL backend's state on its worker thread, the context and
// every GL object, and the operations on them. Its methods live by concern:
// resources.cpp (textures, targets, uploads, read-backs, programs), passes.cpp
// (the full-screen stages), look_passes.cpp (the look's), gl_rasterizer.cpp
// (the G-buffer and back-face passes). A march whose GL form is more than one
// program drawn over the frame has its passes in its own folder
// (MarchInfo::gl_trace; native/marches/hiz/gl_passes.cpp), which use the
// section "for a march's own passes" below. Only worker.cpp's thread ever
// calls any of them.
#pragma once
#include <cstddef>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "gl/egl_context.h"
#include "gl/program.h"
#include "glint/image.h"
#include "glint/marches.h"
#include "glint/options.h"
#include "glint/raster.h"
#include "glint/stages.h"

namespace glint::gl {

inline std::string mib(double bytes) {
  char buf[32];
  const double m = bytes / (1024.0 * 1024.0);
  std::snprintf(buf, sizeof buf, m < 10.0 ? "%.1f" : "%.0f", m);
  return buf;
}

inline std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

inline double rgba32f_bytes(int w, int h) { return static_cast<double>(w) * h * 16.0; }


class GlState {
 public:
  struct Texture {
    GLuint id = 0;
    int w = 0, h = 0;
  };
  explicit GlState(const std::string& egl_library);

  ~GlState();

  const ContextInfo& info() const { return ctx_.info(); }
  const Api& api() const { return gl_; }

  // A trace: the march's own passes where its row has them (gl_trace), else
  // its gl_program drawn once over the frame.
  Image trace(const TraceInputs& in, const TraceOptions& opt);

  Image reflection_color(const Image& uv, const Image& color);

  Image box_blur(const Image& src, const BlurOptions& opt, const int* region);

  // The split-sum table as a kEnvBrdfSize^2 texture, uploaded once.
  const Texture& env_brdf_texture();

  Image specular_weight(const Image& position, const Image& normal, const Image& specular,
                        const Mat4& projection);

  // The reflection colour's 2x2 box chain, every level rendered on the GPU
  // from the one below (as the Hi-Z pyramid is), then one lookup pass.
  Image cone_blur(const Image& color, const Image& uv, const Image& specular, const MirrorScale* mirror);

  Image reflection(const Image& color, const Image* blurred, const Image& specular, const Image* weight);

  Image combine(const Image& base, const Image& refl, Combine mode, const Image* specular_base,
                const Image* coverage);

  GBufferImages rasterize(const RasterInputs& in);

  void compile_for_test(const std::string& entry);
  // Compiles `source` (a test's own embedded shader) as the entry `entry`.
  void compile_source_for_test(const std::string& entry, const std::string& source, FileNameFn file_name);

  // --- for a march's own passes (MarchInfo::gl_trace) ------------------------
  // The helpers every pass above uses, public so that a march's passes, in
  // its folder, are written with them too.
  // Textures are kept between calls and reallocated only when the size
  // changes, so a sequence of frames allocates once. Every pass uses the
  // same few slots, so a large frame's memory is given back as soon as a
  // smaller one runs.
  enum Slot { kIn0, kIn1, kIn2, kOut, kAux, kSlots };

  // A trace's inputs as trace() uploads them: position, normal, the specular
  // buffer where given, the back-face layer where given and the march reads
  // it; `count` textures in all (for the size and memory messages).
  struct TraceTextures {
    const Texture* pos = nullptr;
    const Texture* nrm = nullptr;
    const Texture* spec = nullptr;
    const Texture* back = nullptr;
    int count = 0;
  };
  TraceTextures upload_trace_inputs(const TraceInputs& in, const MarchInfo& info);

  // Every uniform of a trace program `prog` that trace_common.glsl declares,
  // on the texture units upload_trace_inputs() and trace() use (0-2).
  void trace_uniforms(GLuint prog, const TraceInputs& in, const TraceOptions& opt, const TraceTextures& t);

  // GL objects a march's passes keep between frames (the hiz march's
  // pyramid and list of rays): one set per march, made on first use and
  // released with the context.
  struct MarchObjects {
    virtual ~MarchObjects() = default;
    virtual void release(const Api& gl) = 0;
  };
  template <class T>
  T& march_objects(March m) {
    std::unique_ptr<MarchObjects>& o = march_objects_[static_cast<int>(m)];
    if (!o) o = std::make_unique<T>();
    return static_cast<T&>(*o);
  }

  // A w x h RGBA32F texture in `slot` (or a march's own `t`), allocated if
  // its size changed. Allocation errors are checked in every build: running
  // out of memory is an expected outcome for large frames, not a bug.
  Texture& target(Slot slot, int w, int h, const char* pass, int textures);
  Texture& target(Texture& t, int w, int h, const char* pass, int textures);

  Texture& upload(Slot slot, const Image& img, const char* pass, int textures);

  struct Pyramid {
    GLuint id = 0;
    int w = 0, h = 0, levels = 0;
  };
  // (Re)allocate `t` as a `format` texture of w x h with every mip level down
  // to 1x1, unless it already is one: kept between frames. `stage` and
  // `images` size the checks and the out-of-memory error; `name` the others.
  void mip_target(Pyramid& t, int w, int h, GLenum format, const char* stage, int images, const char* name);

  // `second`, when given, is written at location 1 (level 0, same size).
  void attach_level(GLuint tex, int level, const Texture* second = nullptr);
  // Levels 1..levels-1 of `tex`, each drawn by `reduce` from the level below
  // (u_sizes = source w, h, this level's w, h), which it reads as image unit 0
  // (`format`, u_src): no level is sampled while it is rendered, and on
  // llvmpipe an imageLoad costs much less than a texelFetch (the hiz
  // pyramid's reductions took about 45% less time).
  void reduce_levels(GLuint tex, int levels, GLenum format, GLuint reduce, int w, int h);

  // `bytes` of `data` (or uninitialised, for nullptr) into `buffer`, generated
  // on first use and bound to `target`; GL_OUT_OF_MEMORY is an Error naming `what`.
  void buffer_data(GLuint& buffer, GLenum target, size_t bytes, const void* data, const char* what,
                   GLenum usage = GL_STREAM_DRAW);

  // After every pass in debug builds; release builds skip the round trip.
  void debug_check(const std::string& what);

  GLint loc(GLuint prog, const char* name) { return gl_.GetUniformLocation(prog, name); }

  void bind(GLuint prog, const char* sampler, int unit, const Texture& t, GLint filter, GLint wrap);

  // `vert` + `frag`, or a compute shader (.comp) alone, compiled on first use
  // and kept (every fragment shader is used with one vertex shader only).
  GLuint program(const std::string& frag, const char* vert = "fullscreen.vert");

  void attach(const Texture& t);

  void draw(int w, int h);

  // Enough groups of the compute program `prog` to run w x h invocations, at
  // the work group size its shader declares (asked of GL: the shader alone says it).
  void dispatch(GLuint prog, int w, int h);

  // Reads the colour attachment `attachment` of the bound framebuffer.
  Image read(int w, int h, GLenum attachment, const char* pass);

  Image draw_and_read(int w, int h, const char* pass, int textures);

 private:
  void release(Texture& t);

  // Drains the GL error queue; throws on the first error with `what`.
  void check(const std::string& what);

  // The texture limits, before any allocation: an 8K frame on a GL whose
  // limit is 4K fails here, with the numbers, instead of inside the driver.
  void check_size(int w, int h, const char* pass, int textures);

  [[noreturn]] void out_of_memory(int w, int h, const char* pass, int textures);

  // Binding a texture to work on it replaces what the active unit held, and
  // the passes' inputs sit on units 0..3: uploads and allocations use a unit
  // no pass samples from.
  void scratch_unit() { gl_.ActiveTexture(GL_TEXTURE0 + 15); }

  // --- rasterizer objects, kept between frames like the textures -----------
  // A framebuffer of `colors` RGBA32F targets and a DEPTH32F buffer: the
  // G-buffer (3 colours) and the back-face layer (1, or 2 with its albedo)
  // are both one of these.
  struct RasterTargets {
    GLuint fbo = 0, depth = 0, color[3] = {0, 0, 0};
    int w = 0, h = 0, colors = 0;
  };
  RasterTargets raster_;  // the G-buffer
  RasterTargets back_;    // the back-face layer
  GLuint raster_vao_ = 0;
  // positions, normals, uvs, tangents, triangle material, material table, material albedo
  GLuint buffers_[7] = {0, 0, 0, 0, 0, 0, 0};
  std::vector<GLuint> normal_map_textures_;

  void release_targets(RasterTargets& t);

  void release_raster();

  // (Re)allocates `t` for a w x h frame when its size or colour count
  // changed. `what` names it in errors ("the G-buffer"), `pass` is the stage
  // for out-of-memory ones.
  void raster_targets(RasterTargets& t, int colors, int w, int h, const char* what, const char* pass);
  // The steps of rasterize(), in order (gl_rasterizer.cpp).
  void upload_mesh(const RasterInputs& in, const std::vector<float>& positions, const std::vector<float>& normals);
  void upload_normal_maps(const std::vector<Image>& maps);
  void draw_gbuffer(const RasterInputs& in, double base, double depth_scale, const float* proj);
  void rasterize_back(const RasterInputs& in, double base, double depth_scale, const float* proj,
                      GBufferImages& out);

  EglContext ctx_;
  const Api& gl_;
  GLuint empty_vao_ = 0;
  GLuint fbo_ = 0;
  Texture textures_[kSlots];
  Pyramid cone_chain_;  // RGBA32F, every level down to 1x1
  Texture env_brdf_;
  std::map<std::string, GLuint> programs_;
  std::map<int, std::unique_ptr<MarchObjects>> march_objects_;  // by March
};

}  // namespace glint::gl
