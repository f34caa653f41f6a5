// GlState: the full-screen passes of the pipeline, one fragment program each:
// a march's trace (its own passes where it has them: MarchInfo::gl_trace) and
// the stages after it. See gl_state.h.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "gl/gl_state.h"
#include "glint/errors.h"
#include "glint/marches.h"

namespace glint::gl {

Image GlState::trace(const TraceInputs& in, const TraceOptions& opt) {
  const MarchInfo& info = march_info(opt.march);
  if (info.gl_trace) return info.gl_trace(*this, in, opt);
  const TraceTextures t = upload_trace_inputs(in, info);
  const GLuint prog = program(info.gl_program);
  trace_uniforms(prog, in, opt, t);
  gl_.UseProgram(prog);
  return draw_and_read(in.position.width, in.position.height, info.name, t.count);
}

GlState::TraceTextures GlState::upload_trace_inputs(const TraceInputs& in, const MarchInfo& info) {
  TraceTextures t;
  t.count = in.specular ? 4 : 3;
  t.pos = &upload(kIn0, in.position, "trace", t.count);
  t.nrm = &upload(kIn1, in.normal, "trace", t.count);
  t.spec = in.specular ? &upload(kIn2, *in.specular, "trace", t.count) : nullptr;
  t.back = in.back_position && info.uses_back_position ? &upload(kAux, *in.back_position, "trace", t.count + 1)
                                                       : nullptr;
  return t;
}

void GlState::trace_uniforms(GLuint prog, const TraceInputs& in, const TraceOptions& opt, const TraceTextures& t) {
  gl_.UseProgram(prog);
  bind(prog, "u_position", 0, *t.pos, GL_NEAREST, GL_CLAMP_TO_EDGE);
  bind(prog, "u_normal", 1, *t.nrm, GL_NEAREST, GL_CLAMP_TO_EDGE);
  // An unused sampler still needs a complete texture bound; reuse the normal one.
  bind(prog, "u_specular", 2, t.spec ? *t.spec : *t.nrm, GL_NEAREST, GL_CLAMP_TO_EDGE);
  gl_.Uniform1i(loc(prog, "u_has_specular"), t.spec ? 1 : 0);
  float pf[16];
  for (int i = 0; i < 16; ++i) pf[i] = static_cast<float>(in.projection.m[i]);
  gl_.Uniform1fv(loc(prog, "u_proj"), 16, pf);
  gl_.Uniform1dv(loc(prog, "u_projd"), 16, in.projection.m.data());
  gl_.Uniform1i(loc(prog, "u_kind"), static_cast<int>(classify_projection(in.projection)));
  const CameraEye eye = camera_eye(in.projection);
  gl_.Uniform1i(loc(prog, "u_eye_kind"), static_cast<int>(eye.kind));
  gl_.Uniform3f(loc(prog, "u_eye"), eye.eye[0], eye.eye[1], eye.eye[2]);
  gl_.Uniform2f(loc(prog, "u_size"), static_cast<float>(in.position.width),
                static_cast<float>(in.position.height));
  gl_.Uniform1f(loc(prog, "u_max_distance"), opt.max_distance);
  gl_.Uniform1f(loc(prog, "u_thickness"), opt.thickness);
  gl_.Uniform1i(loc(prog, "u_steps"), opt.steps);
  const float r = opt.resolution;
  gl_.Uniform1f(loc(prog, "u_resolution"), r < 0.0f ? 0.0f : (r > 1.0f ? 1.0f : r));
}

void GlState::reduce_levels(GLuint tex, int levels, GLenum format, GLuint reduce, int w, int h) {
  gl_.UseProgram(reduce);
  int sw = w, sh = h;
  for (int level = 1; level < levels; ++level) {
    const int dw = std::max(1, sw / 2), dh = std::max(1, sh / 2);
    gl_.BindImageTexture(0, tex, level - 1, GL_FALSE, 0, GL_READ_ONLY, format);
    gl_.Uniform4i(loc(reduce, "u_sizes"), sw, sh, dw, dh);
    attach_level(tex, level);
    draw(dw, dh);
    sw = dw;
    sh = dh;
  }
}

Image GlState::reflection_color(const Image& uv, const Image& color) {
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

Image GlState::box_blur(const Image& src, const BlurOptions& opt, const int* region) {
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

Image GlState::reflection(const Image& color, const Image* blurred, const Image& specular,
                          const Image* weight) {
  const int textures = 3 + (blurred ? 1 : 0) + (weight ? 1 : 0);
  const Texture& c = upload(kIn0, color, "reflection", textures);
  const Texture& s = upload(kIn2, specular, "reflection", textures);
  // An unused sampler still needs a complete texture bound: the colour stands in.
  const Texture& b = blurred ? upload(kIn1, *blurred, "reflection", textures) : c;
  const Texture& wt = weight ? upload(kAux, *weight, "reflection", textures) : c;
  const GLuint prog = program("reflection.frag");
  gl_.UseProgram(prog);
  bind(prog, "u_color", 0, c, GL_NEAREST, GL_CLAMP_TO_EDGE);
  bind(prog, "u_blurred", 1, b, GL_NEAREST, GL_CLAMP_TO_EDGE);
  bind(prog, "u_specular", 2, s, GL_NEAREST, GL_CLAMP_TO_EDGE);
  bind(prog, "u_weight", 3, wt, GL_NEAREST, GL_CLAMP_TO_EDGE);
  gl_.Uniform1i(loc(prog, "u_has_blurred"), blurred ? 1 : 0);
  gl_.Uniform1i(loc(prog, "u_has_weight"), weight ? 1 : 0);
  return draw_and_read(color.width, color.height, "reflection", textures);
}

Image GlState::combine(const Image& base, const Image& refl, Combine mode, const Image* specular_base,
                       const Image* coverage) {
  const int textures = specular_base ? 5 : 3;
  const Texture& b = upload(kIn0, base, "combine", textures);
  const Texture& r = upload(kIn1, refl, "combine", textures);
  const Texture& sb = specular_base ? upload(kIn2, *specular_base, "combine", textures) : b;
  const Texture& cov = specular_base ? upload(kAux, *coverage, "combine", textures) : b;
  const GLuint prog = program("combine.frag");
  gl_.UseProgram(prog);
  bind(prog, "u_base", 0, b, GL_NEAREST, GL_CLAMP_TO_EDGE);
  bind(prog, "u_reflection", 1, r, GL_NEAREST, GL_CLAMP_TO_EDGE);
  bind(prog, "u_specular_base", 2, sb, GL_NEAREST, GL_CLAMP_TO_EDGE);
  bind(prog, "u_coverage", 3, cov, GL_NEAREST, GL_CLAMP_TO_EDGE);
  gl_.Uniform1i(loc(prog, "u_mode"), mode == Combine::Over ? 0 : 1);
  gl_.Uniform1i(loc(prog, "u_has_specular_base"), specular_base ? 1 : 0);
  return draw_and_read(base.width, base.height, "combine", textures);
}

}  // namespace glint::gl
