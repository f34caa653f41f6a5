// The "hiz" march on the GL backend: the row's gl_trace. The pyramid
// (hiz_base.frag, then hiz_reduce.frag per level), then the walk
// (trace_hiz.frag) over every pixel, or with resolution <= 0.5 over a quarter
// of them, spread by trace_hiz_fill.comp and the rest walked by
// trace_hiz_list.comp; with antialias > 0 the outlines' extra rays
// (hiz_outline_*.comp) in the same frame; then the one read-back
// (docs/gl-backend.md lists the passes). Built with the GL backend only; it
// uses GlState's section for a march's own passes.
#include <algorithm>
#include <cstddef>
#include <string>

#include "gl/gl_state.h"
#include "glint/errors.h"
#include "glint/marches.h"
#include "hiz.h"

namespace glint::gl {
namespace {

// What the march keeps between frames, reallocated when the size changes.
struct HizObjects : GlState::MarchObjects {
  GlState::Pyramid pyramid;  // RG32F: the min/max depth, every level down to 1x1
  GlState::Texture planes;   // the plane normals (hiz_base.frag's second target)
  GlState::Texture quarter;  // the traced quarter of the pixels, when reusing rays
  // hiz_rays.glsl's list of rays, grown when a larger frame needs it.
  GLuint rays = 0;
  size_t rays_bytes = 0;
  // hiz_outline.glsl's buffers, grown the same way: the list of outline
  // pixels, a batch's samples, and every batch's dispatch arguments.
  GLuint outline = 0, samples = 0, outline_args = 0;
  size_t outline_bytes = 0, samples_bytes = 0, outline_args_bytes = 0;

  void release(const Api& gl) override {
    if (pyramid.id) gl.DeleteTextures(1, &pyramid.id);
    if (planes.id) gl.DeleteTextures(1, &planes.id);
    if (quarter.id) gl.DeleteTextures(1, &quarter.id);
    for (GLuint* b : {&rays, &outline, &samples, &outline_args})
      if (*b) gl.DeleteBuffers(1, b);
    pyramid = GlState::Pyramid{};
    planes = quarter = GlState::Texture{};
    rays = outline = samples = outline_args = 0;
    rays_bytes = outline_bytes = samples_bytes = outline_args_bytes = 0;
  }
};

// `buffer`, with room for `bytes`, bound as GL_SHADER_STORAGE_BUFFER: kept
// between frames, and reallocated only to grow.
void storage(GlState& s, GLuint& buffer, size_t& have, size_t bytes, const char* what) {
  if (bytes > have) {
    have = 0;  // until the larger store exists
    s.buffer_data(buffer, GL_SHADER_STORAGE_BUFFER, bytes, nullptr, what, GL_DYNAMIC_COPY);
    have = bytes;
  } else {
    s.api().BindBuffer(GL_SHADER_STORAGE_BUFFER, buffer);
  }
}

// The most bytes of a buffer a shader sees (GL_MAX_SHADER_STORAGE_BLOCK_SIZE:
// 2^24 at the least; llvmpipe 2^27); 0 where GL does not say.
size_t storage_block_limit(const Api& gl) {
  GLint64 limit = 0;
  gl.GetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &limit);
  return limit > 0 ? static_cast<size_t>(limit) : 0;
}

// The uniforms hiz_common.glsl declares.
void bind_hiz_inputs(GlState& s, GLuint prog, const TraceInputs& in, const GlState::Texture& pos,
                     const GlState::Texture* back) {
  const Api& gl = s.api();
  const Mat4 inv = inverse(in.projection);
  float f[16];
  for (int k = 0; k < 16; ++k) f[k] = static_cast<float>(inv.m[k]);
  gl.Uniform1fv(s.loc(prog, "u_inv"), 16, f);
  // An unused sampler still needs a complete texture: the position stands in.
  s.bind(prog, "u_back", 3, back ? *back : pos, GL_NEAREST, GL_CLAMP_TO_EDGE);
  gl.Uniform1i(s.loc(prog, "u_has_back"), back ? 1 : 0);
}

// The pyramid: level 0 from the G-buffer, then each level from the one
// below, all on the GPU (reduce_levels()). The CPU builds the same cells
// (build_hiz_pyramid(), hiz.h).
void build_pyramid(GlState& s, HizObjects& o, const TraceInputs& in, const TraceOptions& opt,
                   const GlState::TraceTextures& t) {
  const Api& gl = s.api();
  const int w = in.position.width, h = in.position.height;
  s.mip_target(o.pyramid, w, h, GL_RG32F, "the hiz pyramid", 1, "the hiz pyramid");
  const GlState::Texture& planes = s.target(o.planes, w, h, "the hiz plane normals", 1);
  // The base level and the plane normals (which the walk reads) in one pass.
  const GLuint base = s.program("hiz_base.frag");
  gl.UseProgram(base);
  gl.BindImageTexture(0, t.pos->id, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  gl.BindImageTexture(1, t.nrm->id, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  bind_hiz_inputs(s, base, in, *t.pos, t.back);
  gl.Uniform2f(s.loc(base, "u_size"), static_cast<float>(w), static_cast<float>(h));
  gl.Uniform1f(s.loc(base, "u_thickness"), opt.thickness);
  s.attach_level(o.pyramid.id, 0, &planes);
  s.draw(w, h);
  s.reduce_levels(o.pyramid.id, o.pyramid.levels, GL_RG32F, s.program("hiz_reduce.frag"), w, h);
  s.debug_check("hiz pyramid");
}

// Every uniform of the walk's program `prog` (trace_hiz.frag or
// trace_hiz_list.comp): the trace's, hiz_common.glsl's, the pyramid and the
// plane normals.
void walk_uniforms(GlState& s, const HizObjects& o, GLuint prog, const TraceInputs& in, const TraceOptions& opt,
                   const GlState::TraceTextures& t) {
  const Api& gl = s.api();
  s.trace_uniforms(prog, in, opt, t);
  bind_hiz_inputs(s, prog, in, *t.pos, t.back);
  gl.ActiveTexture(GL_TEXTURE0 + 4);
  gl.BindTexture(GL_TEXTURE_2D, o.pyramid.id);
  gl.Uniform1i(s.loc(prog, "u_pyramid"), 4);
  gl.Uniform1i(s.loc(prog, "u_levels"), o.pyramid.levels);
  gl.BindImageTexture(5, t.pos->id, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  gl.BindImageTexture(6, o.planes.id, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  gl.Uniform1i(s.loc(prog, "u_pass"), 0);
  gl.Uniform1i(s.loc(prog, "u_blocked"), opt.blocked == Blocked::Occluder ? 1 : 0);
}

// hiz_rays.glsl's list for a w x h frame, with room for every pixel, bound as
// GL_SHADER_STORAGE_BUFFER with its header reset.
GLuint ray_list(GlState& s, HizObjects& o, int w, int h) {
  const Api& gl = s.api();
  // The traced quarter is never listed: room for the other pixels only.
  const size_t all = static_cast<size_t>(w) * static_cast<size_t>(h);
  const size_t quarter = static_cast<size_t>((w + 1) / 2) * static_cast<size_t>((h + 1) / 2);
  const size_t bytes = (4 + all - quarter) * sizeof(GLuint);
  // A shader sees at most GL_MAX_SHADER_STORAGE_BLOCK_SIZE bytes of the
  // buffer (llvmpipe's 2^27 is enough for 8K): past it the list would be cut
  // silently, so the frame is refused, as check_size() does.
  const size_t limit = storage_block_limit(gl);
  if (limit > 0 && bytes > limit)
    throw Error("glint GL: " + size_text(w, h) + " is too large for the hiz march's reuse of rays on " +
                s.info().renderer + ": its list of rays needs " + mib(double(bytes)) +
                " MiB, GL_MAX_SHADER_STORAGE_BLOCK_SIZE is " + mib(double(limit)) +
                " MiB. Use resolution above 0.5 or backend=\"cpu\" for this size.");
  storage(s, o.rays, o.rays_bytes, bytes, "hiz march's list of rays");
  // groups_x, groups_y, groups_z, count (hiz_rays.glsl).
  const GLuint header[4] = {0, 1, 1, 0};
  gl.BufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof header, header);
  return o.rays;
}

// Reusing rays (hiz_reuses_rays()): `prog` (trace_hiz.frag) traces a quarter
// of the pixels, trace_hiz_fill.comp spreads them and lists the pixels where
// they disagree (hiz_rays.glsl), hiz_rays_args.comp sizes the dispatch and
// `list` (trace_hiz_list.comp) traces the listed pixels, a ray per lane. Both
// programs have every uniform set. The frame is left in GlState::kOut,
// unread, with the writes of the last pass made visible to image loads.
const GlState::Texture& trace_reusing(GlState& s, HizObjects& o, GLuint prog, GLuint list,
                                      const GlState::TraceTextures& t, int w, int h) {
  const Api& gl = s.api();
  const char* pass = "hiz";
  const int textures = t.count;
  const GlState::Texture& pos = *t.pos;
  const GlState::Texture& nrm = *t.nrm;
  const GlState::Texture* spec = t.spec;
  // 1. Pixel (2x, 2y) of the frame into pixel (x, y) of a half-size target.
  gl.UseProgram(prog);
  gl.Uniform1i(s.loc(prog, "u_pass"), 1);
  const int cw = (w + 1) / 2, ch = (h + 1) / 2;
  const GlState::Texture& quarter = s.target(o.quarter, cw, ch, pass, textures + 2);
  s.attach(quarter);
  s.draw(cw, ch);
  // 2. Every 2x2 quad: the quarter spread where it agrees; the rest listed.
  const GlState::Texture& out = s.target(GlState::kOut, w, h, pass, textures + 2);
  const GLuint rays = ray_list(s, o, w, h);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, rays);
  gl.BindImageTexture(0, out.id, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
  const GLuint fill = s.program("trace_hiz_fill.comp");
  gl.UseProgram(fill);
  gl.BindImageTexture(1, pos.id, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  gl.BindImageTexture(2, nrm.id, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  // An unused image unit still needs an image bound: the normals stand in.
  gl.BindImageTexture(3, (spec ? *spec : nrm).id, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  gl.BindImageTexture(4, quarter.id, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  gl.Uniform1i(s.loc(fill, "u_has_specular"), spec ? 1 : 0);
  gl.Uniform2f(s.loc(fill, "u_size"), static_cast<float>(w), static_cast<float>(h));
  s.dispatch(fill, cw, ch);
  // 3. The dispatch's size from the list's length, on the GPU: no read-back.
  gl.MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  gl.UseProgram(s.program("hiz_rays_args.comp"));
  gl.DispatchCompute(1, 1, 1);
  // 4. The listed pixels' walks, written into the frame beside the fill's.
  gl.MemoryBarrier(GL_COMMAND_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
  gl.UseProgram(list);
  gl.BindBuffer(GL_DISPATCH_INDIRECT_BUFFER, rays);
  gl.DispatchComputeIndirect(0);
  gl.MemoryBarrier(GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
  s.debug_check(pass);
  return out;
}

// The antialiased outlines (trace_hiz() in march_hiz.cpp, after every pixel's
// trace): `out`, the traced frame, gets the outline pixels' extra rays, all
// on the GPU. hiz_outline_find.comp lists the pixels, hiz_outline_args.comp
// sizes each batch's dispatches, and per batch hiz_outline_trace.comp walks
// the samples and hiz_outline_resolve.comp writes the filtered reports back
// into `out`. `walk` (hiz_outline_trace.comp) has walk_uniforms() set.
void antialias_outlines(GlState& s, HizObjects& o, GLuint walk, const TraceOptions& opt,
                        const GlState::TraceTextures& t, const GlState::Texture& out, int w, int h) {
  const Api& gl = s.api();
  const int k = std::min(opt.antialias, 4);
  const size_t pixels = static_cast<size_t>(w) * static_cast<size_t>(h);
  const size_t limit = storage_block_limit(gl);
  // Every pixel may be on an outline (a checkerboard of hits and misses),
  // and the list cannot be cut without losing pixels: refused past the
  // limit, as ray_list() refuses its list.
  const size_t list_bytes = (1 + pixels) * sizeof(GLuint);
  // A listed pixel packs x in 16 bits, y in 15 and a flag in the last
  // (hiz_outline.glsl): no OpenGL today allows a texture 32768 high.
  if (w > 65535 || h > 32767)
    throw Error("glint GL: " + size_text(w, h) + " is too large for the hiz march's antialiased outlines "
                "(at most 65535x32767). Use antialias=0 or backend=\"cpu\" for this size.");
  if (limit > 0 && list_bytes > limit)
    throw Error("glint GL: " + size_text(w, h) + " is too large for the hiz march's antialiased outlines on " +
                s.info().renderer + ": their list of pixels needs " + mib(double(list_bytes)) +
                " MiB, GL_MAX_SHADER_STORAGE_BLOCK_SIZE is " + mib(double(limit)) +
                " MiB. Use antialias=0 or backend=\"cpu\" for this size.");
  // The samples, 16 bytes each, are kept for a batch of listed pixels at a
  // time: room for all of them would pass the limit long before the list does
  // (k = 4 at 1440p on llvmpipe), and would be 64 bytes a pixel for outlines
  // that are a few percent of the frame. A quarter of the pixels keeps them
  // at most one RGBA32F frame's size while a frame is still one batch.
  const size_t per_pixel = static_cast<size_t>(k) * 4 * sizeof(float);
  size_t batch = (pixels + 3) / 4;
  if (limit > 0) batch = std::min(batch, limit / per_pixel);
  batch = std::max<size_t>(batch, 1);
  const size_t batches = (pixels + batch - 1) / batch;
  const char* pass = "hiz antialiased outlines";

  storage(s, o.outline, o.outline_bytes, list_bytes, "hiz march's list of outline pixels");
  const GLuint zero = 0;
  gl.BufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof zero, &zero);
  storage(s, o.samples, o.samples_bytes, batch * per_pixel, "hiz march's outline samples");
  storage(s, o.outline_args, o.outline_args_bytes, batches * 6 * sizeof(GLuint),
          "hiz march's outline dispatch arguments");
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, o.outline);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, o.samples);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, o.outline_args);
  gl.BindImageTexture(0, out.id, 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);

  // 1. Every pixel's outline test; the outline's listed.
  const GLuint find = s.program("hiz_outline_find.comp");
  gl.UseProgram(find);
  gl.BindImageTexture(1, t.pos->id, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  gl.BindImageTexture(2, t.nrm->id, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  // An unused image unit still needs an image bound: the normals stand in.
  gl.BindImageTexture(3, (t.spec ? *t.spec : *t.nrm).id, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  gl.Uniform1i(s.loc(find, "u_has_specular"), t.spec ? 1 : 0);
  gl.Uniform2f(s.loc(find, "u_size"), static_cast<float>(w), static_cast<float>(h));
  s.dispatch(find, w, h);

  // 2. Each batch's dispatch sizes from the list's length.
  gl.MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  const GLuint args = s.program("hiz_outline_args.comp");
  gl.UseProgram(args);
  gl.Uniform1i(s.loc(args, "u_per_pixel"), k);
  gl.Uniform1i(s.loc(args, "u_batch"), static_cast<GLint>(batch));
  gl.Uniform1i(s.loc(args, "u_batches"), static_cast<GLint>(batches));
  gl.DispatchCompute(1, 1, 1);

  // 3, 4. Per batch, the samples' walks, then each listed pixel's filter.
  gl.MemoryBarrier(GL_COMMAND_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
  gl.BindBuffer(GL_DISPATCH_INDIRECT_BUFFER, o.outline_args);
  const GLuint resolve = s.program("hiz_outline_resolve.comp");
  gl.UseProgram(resolve);
  gl.Uniform1i(s.loc(resolve, "u_per_pixel"), k);
  gl.Uniform1i(s.loc(resolve, "u_batch"), static_cast<GLint>(batch));
  gl.Uniform2f(s.loc(resolve, "u_size"), static_cast<float>(w), static_cast<float>(h));
  gl.UseProgram(walk);
  gl.Uniform1i(s.loc(walk, "u_per_pixel"), k);
  gl.Uniform1i(s.loc(walk, "u_batch"), static_cast<GLint>(batch));
  for (size_t b = 0; b < batches; ++b) {
    const GLint first = static_cast<GLint>(b * batch);
    const GLintptr at = static_cast<GLintptr>(b * 6 * sizeof(GLuint));
    gl.UseProgram(walk);
    gl.Uniform1i(s.loc(walk, "u_first"), first);
    gl.DispatchComputeIndirect(at);
    gl.MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    gl.UseProgram(resolve);
    gl.Uniform1i(s.loc(resolve, "u_first"), first);
    gl.DispatchComputeIndirect(at + 3 * static_cast<GLintptr>(sizeof(GLuint)));
    // The next batch's walks overwrite the samples just read.
    gl.MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
  }
  gl.MemoryBarrier(GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
  s.debug_check(pass);
}

}  // namespace

Image trace_hiz(GlState& s, const TraceInputs& in, const TraceOptions& opt) {
  const int w = in.position.width, h = in.position.height;
  const MarchInfo& info = march_info(opt.march);
  HizObjects& o = s.march_objects<HizObjects>(info.id);
  const GlState::TraceTextures t = s.upload_trace_inputs(in, info);
  build_pyramid(s, o, in, opt, t);
  const GLuint prog = s.program(info.gl_program);
  walk_uniforms(s, o, prog, in, opt, t);
  const GlState::Texture* out = nullptr;
  if (hiz_reuses_rays(opt)) {
    const GLuint list = s.program("trace_hiz_list.comp");
    walk_uniforms(s, o, list, in, opt, t);
    out = &trace_reusing(s, o, prog, list, t, w, h);
  } else {
    // Drawn into the frame, not read yet: the outlines' passes may follow.
    s.api().UseProgram(prog);
    out = &s.target(GlState::kOut, w, h, info.name, t.count);
    s.attach(*out);
    s.draw(w, h);
    s.debug_check(info.name);
  }
  if (opt.antialias > 0) {
    const GLuint walk = s.program("hiz_outline_trace.comp");
    walk_uniforms(s, o, walk, in, opt, t);
    antialias_outlines(s, o, walk, opt, t, *out, w, h);
  }
  s.attach(*out);
  return s.read(w, h, GL_COLOR_ATTACHMENT0, info.name);
}

}  // namespace glint::gl
