// GlState: the passes of the physically based look, the specular weight and
// the cone blur (docs/look-core.md). See gl_state.h.
#include <algorithm>
#include <string>
#include <vector>

#include "gl/gl_state.h"
#include "glint/brdf.h"
#include "glint/errors.h"
#include "glint/material.h"

namespace glint::gl {

const GlState::Texture& GlState::env_brdf_texture() {
  if (env_brdf_.id) return env_brdf_;
  const std::vector<float>& table = env_brdf_table();
  while (gl_.GetError() != GL_NO_ERROR) {
  }
  gl_.GenTextures(1, &env_brdf_.id);
  scratch_unit();
  gl_.BindTexture(GL_TEXTURE_2D, env_brdf_.id);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
  gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
  gl_.TexImage2D(GL_TEXTURE_2D, 0, GL_RG32F, kEnvBrdfSize, kEnvBrdfSize, 0, GL_RG, GL_FLOAT, table.data());
  const GLenum err = gl_.GetError();
  if (err != GL_NO_ERROR) {
    release(env_brdf_);
    throw Error(std::string("glint GL: uploading the split-sum table failed: ") + gl_error_name(err));
  }
  env_brdf_.w = env_brdf_.h = kEnvBrdfSize;
  return env_brdf_;
}

Image GlState::specular_weight(const Image& position, const Image& normal, const Image& specular,
                               const Mat4& projection) {
  const Texture& pos = upload(kIn0, position, "specular_weight", 4);
  const Texture& nrm = upload(kIn1, normal, "specular_weight", 4);
  const Texture& spec = upload(kIn2, specular, "specular_weight", 4);
  const Texture& lut = env_brdf_texture();
  const GLuint prog = program("specular_weight.frag");
  gl_.UseProgram(prog);
  bind(prog, "u_position", 0, pos, GL_NEAREST, GL_CLAMP_TO_EDGE);
  bind(prog, "u_normal", 1, nrm, GL_NEAREST, GL_CLAMP_TO_EDGE);
  bind(prog, "u_specular", 2, spec, GL_NEAREST, GL_CLAMP_TO_EDGE);
  bind(prog, "u_env_brdf", 3, lut, GL_NEAREST, GL_CLAMP_TO_EDGE);
  const CameraEye eye = camera_eye(projection);
  gl_.Uniform1i(loc(prog, "u_eye_kind"), static_cast<int>(eye.kind));
  gl_.Uniform3f(loc(prog, "u_eye"), eye.eye[0], eye.eye[1], eye.eye[2]);
  return draw_and_read(position.width, position.height, "specular_weight", 4);
}

Image GlState::cone_blur(const Image& color, const Image& uv, const Image& specular, const MirrorScale* mirror) {
  const int w = color.width, h = color.height;
  // The chain: an RGBA32F texture with every level, kept between frames.
  mip_target(cone_chain_, w, h, GL_RGBA32F, "cone_blur", 5, "the cone blur's chain");
  const GLuint chain = cone_chain_.id;
  scratch_unit();
  gl_.BindTexture(GL_TEXTURE_2D, chain);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, 0);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, cone_chain_.levels - 1);
  gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
  gl_.TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, color.data.data());

  // Each level from the one below (reduce_levels: no pass samples what it writes).
  reduce_levels(chain, cone_chain_.levels, GL_RGBA32F, program("cone_reduce.frag"), w, h);
  debug_check("cone_blur chain");

  const Texture& t_uv = upload(kIn0, uv, "cone_blur", 5);
  const Texture& t_spec = upload(kIn1, specular, "cone_blur", 5);
  const GLuint prog = program("cone_blur.frag");
  gl_.UseProgram(prog);
  gl_.ActiveTexture(GL_TEXTURE0 + 0);
  gl_.BindTexture(GL_TEXTURE_2D, chain);
  gl_.Uniform1i(loc(prog, "u_chain"), 0);
  bind(prog, "u_uv", 1, t_uv, GL_NEAREST, GL_CLAMP_TO_EDGE);
  bind(prog, "u_specular", 2, t_spec, GL_NEAREST, GL_CLAMP_TO_EDGE);
  gl_.Uniform1i(loc(prog, "u_last"), cone_chain_.levels - 1);
  // The flat mirror's bound (cone_lod_at()): the positions and the camera.
  const bool bounded = mirror && mirror->position;
  gl_.Uniform1i(loc(prog, "u_bounded"), bounded ? 1 : 0);
  if (bounded) {
    const Texture& t_pos = upload(kIn2, *mirror->position, "cone_blur", 5);
    bind(prog, "u_position", 3, t_pos, GL_NEAREST, GL_CLAMP_TO_EDGE);
    gl_.Uniform1i(loc(prog, "u_eye_kind"), static_cast<int>(mirror->eye.kind));
    gl_.Uniform3f(loc(prog, "u_eye"), mirror->eye.eye[0], mirror->eye.eye[1], mirror->eye.eye[2]);
    gl_.Uniform1f(loc(prog, "u_pixels_per_unit"), mirror->pixels_per_unit);
    gl_.Uniform4f(loc(prog, "u_w_row"), mirror->w_row[0], mirror->w_row[1], mirror->w_row[2], mirror->w_row[3]);
  } else {
    // A sampler must name a texture unit of its own type even when unread.
    bind(prog, "u_position", 3, t_uv, GL_NEAREST, GL_CLAMP_TO_EDGE);
  }
  return draw_and_read(w, h, "cone_blur", 5);
}

}  // namespace glint::gl
