// GlState: G-buffers from triangles (one MRT pass) and the back-face layer.
// See gl_state.h.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "gl/gl_state.h"
#include "glint/errors.h"

namespace glint::gl {

void GlState::release_targets(RasterTargets& t) {
  if (t.fbo) gl_.DeleteFramebuffers(1, &t.fbo);
  if (t.depth) gl_.DeleteRenderbuffers(1, &t.depth);
  for (GLuint& c : t.color)
    if (c) gl_.DeleteTextures(1, &c);
  t = RasterTargets{};
}

void GlState::release_raster() {
  release_targets(raster_);
  release_targets(back_);
  if (raster_vao_) gl_.DeleteVertexArrays(1, &raster_vao_);
  raster_vao_ = 0;
  for (GLuint& b : buffers_)
    if (b) gl_.DeleteBuffers(1, &b);
  std::fill(std::begin(buffers_), std::end(buffers_), 0u);
  if (!normal_map_textures_.empty())
    gl_.DeleteTextures(static_cast<GLsizei>(normal_map_textures_.size()), normal_map_textures_.data());
  normal_map_textures_.clear();
}

void GlState::raster_targets(RasterTargets& t, int colors, int w, int h, const char* what,
                             const char* pass) {
  if (t.fbo && t.w == w && t.h == h && t.colors == colors) return;
  release_targets(t);
  const ContextInfo& ci = info();
  if (w > ci.max_renderbuffer_size || h > ci.max_renderbuffer_size) {
    throw Error("glint GL: " + size_text(w, h) + " is larger than this OpenGL's depth buffers allow (" +
                "GL_MAX_RENDERBUFFER_SIZE " + std::to_string(ci.max_renderbuffer_size) + " on " +
                ci.renderer + "). Use backend=\"cpu\" for this size.");
  }
  check_size(w, h, pass, colors + 1);
  while (gl_.GetError() != GL_NO_ERROR) {
  }
  gl_.GenFramebuffers(1, &t.fbo);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, t.fbo);
  gl_.GenTextures(colors, t.color);
  scratch_unit();
  for (int i = 0; i < colors; ++i) {
    gl_.BindTexture(GL_TEXTURE_2D, t.color[i]);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl_.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, nullptr);
    gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + i, GL_TEXTURE_2D, t.color[i], 0);
  }
  gl_.GenRenderbuffers(1, &t.depth);
  gl_.BindRenderbuffer(GL_RENDERBUFFER, t.depth);
  gl_.RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
  gl_.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t.depth);
  const GLenum err = gl_.GetError();
  if (err != GL_NO_ERROR) {
    t.w = t.h = 0;
    if (err == GL_OUT_OF_MEMORY) out_of_memory(w, h, pass, colors + 1);
    throw Error(std::string("glint GL: allocating ") + what + " targets failed: " + gl_error_name(err));
  }
  const GLenum status = gl_.CheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw Error(std::string("glint GL: ") + what + " framebuffer (" + std::to_string(colors) +
                " x RGBA32F + DEPTH32F) is incomplete on " + ci.renderer);
  t.w = w;
  t.h = h;
  t.colors = colors;
}

void GlState::buffer_data(GLuint& buffer, GLenum target, size_t bytes, const void* data, const char* what,
                          GLenum usage) {
  if (!buffer) gl_.GenBuffers(1, &buffer);
  gl_.BindBuffer(target, buffer);
  while (gl_.GetError() != GL_NO_ERROR) {
  }
  // Never a zero-sized store (some drivers reject binding one): tiny data is
  // padded in a copy, since GL reads the whole size from `data`.
  unsigned char padded[16] = {};
  if (bytes < sizeof padded) {
    if (bytes && data) std::memcpy(padded, data, bytes);
    data = padded;
    bytes = sizeof padded;
  }
  gl_.BufferData(target, static_cast<GLsizeiptr>(bytes), data, usage);
  const GLenum err = gl_.GetError();
  if (err == GL_OUT_OF_MEMORY)
    throw Error("glint GL: out of memory: the " + std::string(what) + " buffer needs " + mib(double(bytes)) +
                " MiB (GL_OUT_OF_MEMORY on " + info().renderer + ")");
  if (err != GL_NO_ERROR)
    throw Error(std::string("glint GL: uploading the ") + what + " buffer failed: " + gl_error_name(err));
}

namespace {

// The mesh as the G-buffer pass can take it: triangles with a non-finite
// corner are skipped, as on the CPU, by collapsing them to a point (zero
// area covers nothing); corner normals that are non-finite or all zero give
// the face normal everywhere on the CPU, so they are replaced by it here.
// Both copy only when there is such a triangle. Also the range of the
// visible corners' view distances, for the depth mapping.
struct CleanMesh {
  std::vector<float> pos_copy, nrm_copy;  // empty: the mesh's own are fine
  double d_min = 0.0, d_max = 0.0;
};

CleanMesh clean_mesh(const Mesh& mesh) {
  CleanMesh out;
  std::vector<float>& pos_copy = out.pos_copy;  // short names for the loop below
  std::vector<float>& nrm_copy = out.nrm_copy;
  const size_t tris = mesh.triangle_count();
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
      if (!any_vertex || d < out.d_min) out.d_min = d;
      if (!any_vertex || d > out.d_max) out.d_max = d;
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
  return out;
}

// View distance d is stored as (d - base) * scale in the depth buffer.
struct DepthMapping {
  double base, scale;
};

DepthMapping depth_mapping(const Mat4& projection, double d_min, double d_max) {
  // The depth test compares view distances, as the CPU does. A float depth
  // buffer still only takes [0, 1], so the distance is offset and scaled by
  // a power of two: the scaling is exact, and with no offset (all of a
  // perspective camera's visible points lie in front of it) the comparison
  // keeps every bit of the distance.
  // A lower bound of the visible view distances: the near plane for a
  // perspective (> 0) or orthographic camera, else the nearest corner.
  const ProjectionKind kind = classify_projection(projection);
  double lower = d_min;
  if (kind == ProjectionKind::Perspective) {
    lower = 0.0;
  } else if (kind == ProjectionKind::Orthographic) {
    // clip z = -1 on the near plane
    lower = std::max(d_min, (1.0 + projection(2, 3)) / projection(2, 2));
  }
  // Rounded down a little so that float rounding of the base cannot push a
  // visible distance below it (it would be clamped to 0 and tie).
  const double base = lower >= 0.0 ? 0.0 : lower - std::fabs(lower) * 1e-5 - 1e-30;
  int exponent = 0;
  std::frexp(std::max(d_max - base, 1e-30), &exponent);
  const double depth_scale = std::ldexp(1.0, -(exponent + 1));  // (d - base) * scale < 0.5
  return {base, depth_scale};
}

}  // namespace

GBufferImages GlState::rasterize(const RasterInputs& in) {
  const int w = in.width, h = in.height;
  raster_targets(raster_, 3, w, h, "the G-buffer", "rasterize");
  const CleanMesh clean = clean_mesh(in.mesh);
  const DepthMapping depth = depth_mapping(in.projection, clean.d_min, clean.d_max);
  upload_mesh(in, clean.pos_copy.empty() ? in.mesh.positions : clean.pos_copy,
              clean.nrm_copy.empty() ? in.mesh.normals : clean.nrm_copy);
  upload_normal_maps(in.normal_maps);
  float pf[16];
  for (int i = 0; i < 16; ++i) pf[i] = static_cast<float>(in.projection.m[i]);
  draw_gbuffer(in, depth.base, depth.scale, pf);

  GBufferImages out;
  out.position = read(w, h, GL_COLOR_ATTACHMENT0, "rasterize");
  out.normal = read(w, h, GL_COLOR_ATTACHMENT1, "rasterize");
  out.specular = read(w, h, GL_COLOR_ATTACHMENT2, "rasterize");
  if (in.back_layer) rasterize_back(in, depth.base, depth.scale, pf, out);
  return out;
}

// The triangles' arrays, the material table and the vertex array object.
void GlState::upload_mesh(const RasterInputs& in, const std::vector<float>& positions,
                          const std::vector<float>& normals) {
  const Mesh& mesh = in.mesh;
  const size_t tris = mesh.triangle_count();
  // uvs and tangents are only bound when they are there for every triangle
  // (validate() guarantees it wherever a triangle's material has a map).
  bool any_map = tris > 0 && mesh.uvs.size() == tris * 6 && mesh.tangents.size() == tris * 12;
  bool map_used = false;
  for (const Material& m : in.materials) map_used = map_used || m.normal_map >= 0;
  any_map = any_map && map_used;
  buffer_data(buffers_[0], GL_ARRAY_BUFFER, positions.size() * sizeof(float), positions.data(), "positions");
  buffer_data(buffers_[1], GL_ARRAY_BUFFER, normals.size() * sizeof(float), normals.data(), "normals");
  if (any_map) {
    buffer_data(buffers_[2], GL_ARRAY_BUFFER, mesh.uvs.size() * sizeof(float), mesh.uvs.data(), "uvs");
    buffer_data(buffers_[3], GL_ARRAY_BUFFER, mesh.tangents.size() * sizeof(float), mesh.tangents.data(),
                "tangents");
  }
  buffer_data(buffers_[4], GL_SHADER_STORAGE_BUFFER, mesh.material.size() * sizeof(int32_t), mesh.material.data(),
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
  buffer_data(buffers_[5], GL_SHADER_STORAGE_BUFFER, table.size() * sizeof(float), table.data(), "material");
  // Per material: (albedo r, g, b, 1), which the back pass copies as it is,
  // so the GL result is the CPU's bit for bit. A few bytes a material: sent
  // even when unused, so the back pass never has a block without a buffer.
  for (size_t k = 0; k < in.materials.size(); ++k) {
    const Material& m = in.materials[k];
    table[4 * k + 0] = m.albedo[0];
    table[4 * k + 1] = m.albedo[1];
    table[4 * k + 2] = m.albedo[2];
    table[4 * k + 3] = 1.0f;
  }
  buffer_data(buffers_[6], GL_SHADER_STORAGE_BUFFER, table.size() * sizeof(float), table.data(),
              "material albedo");

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
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, buffers_[6]);
}

// Normal maps: one texture each, sampled GL_LINEAR + GL_REPEAT like the
// CPU's sample_normal_map().
void GlState::upload_normal_maps(const std::vector<Image>& maps) {
  if (!normal_map_textures_.empty())
    gl_.DeleteTextures(static_cast<GLsizei>(normal_map_textures_.size()), normal_map_textures_.data());
  normal_map_textures_.assign(maps.size(), 0);
  if (!normal_map_textures_.empty()) {
    gl_.GenTextures(static_cast<GLsizei>(normal_map_textures_.size()), normal_map_textures_.data());
    scratch_unit();
    for (size_t k = 0; k < maps.size(); ++k) {
      const Image& img = maps[k];
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
      throw Error("glint GL: out of memory uploading " + std::to_string(maps.size()) +
                  " normal maps");
    if (err != GL_NO_ERROR)
      throw Error(std::string("glint GL: uploading the normal maps failed: ") + gl_error_name(err));
  }
}

// The G-buffer pass over the uploaded mesh into raster_.
void GlState::draw_gbuffer(const RasterInputs& in, double base, double depth_scale, const float* pf) {
  const Mesh& mesh = in.mesh;
  const size_t tris = mesh.triangle_count();
  const int w = in.width, h = in.height;
  const GLuint prog = program("gbuffer.frag", "gbuffer.vert");
  gl_.UseProgram(prog);
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
}

// The back-face layer: every triangle again into a target of its own, each
// fragment kept only if it is back-facing and behind the front layer's
// surface (read from the front pass's position target, still on the GPU).
// With back_albedo a second target takes the material albedo of the same
// fragment, so the depth test that picks the back position picks its albedo.
void GlState::rasterize_back(const RasterInputs& in, double base, double depth_scale, const float* proj,
                             GBufferImages& out) {
  const int w = in.width, h = in.height;
  const size_t tris = in.mesh.triangle_count();
  const int colors = in.back_albedo ? 2 : 1;
  raster_targets(back_, colors, w, h, "the back-face layer", "rasterize (back-face layer)");
  const GLuint prog = program("gbuffer_back.frag", "gbuffer.vert");
  gl_.UseProgram(prog);
  gl_.Uniform1fv(loc(prog, "u_proj"), 16, proj);
  gl_.Uniform1f(loc(prog, "u_depth_base"), static_cast<float>(base));
  gl_.Uniform1f(loc(prog, "u_depth_scale"), static_cast<float>(depth_scale));
  gl_.ActiveTexture(GL_TEXTURE0 + 1);
  gl_.BindTexture(GL_TEXTURE_2D, raster_.color[0]);
  gl_.Uniform1i(loc(prog, "u_front"), 1);
  gl_.Uniform1i(loc(prog, "u_back_albedo"), in.back_albedo ? 1 : 0);
  // One draw from triangle 0, so the offset is 0; it is set anyway so that
  // the albedo lookup is the front pass's specular lookup, word for word.
  // The material buffers are still bound from upload_mesh().
  gl_.Uniform1i(loc(prog, "u_first_triangle"), 0);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, back_.fbo);
  const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  gl_.DrawBuffers(colors, bufs);
  gl_.Viewport(0, 0, w, h);
  const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  const float one = 1.0f;
  for (int i = 0; i < colors; ++i) gl_.ClearBufferfv(GL_COLOR, i, zero);
  gl_.DepthMask(GL_TRUE);
  gl_.ClearBufferfv(GL_DEPTH, 0, &one);
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthFunc(GL_LESS);
  gl_.BindVertexArray(raster_vao_);
  gl_.DrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(tris * 3));
  gl_.Disable(GL_DEPTH_TEST);
  debug_check("rasterize (back-face layer)");
  out.back_position = read(w, h, GL_COLOR_ATTACHMENT0, "rasterize (back-face layer)");
  if (in.back_albedo) out.back_albedo = read(w, h, GL_COLOR_ATTACHMENT1, "rasterize (back-face layer)");
}

}  // namespace glint::gl
