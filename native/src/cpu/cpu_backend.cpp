// The CPU reference backend: every stage as plain loops over rows, run on a
// small thread pool. This is the backend the others are checked against.
#include <algorithm>
#include <cmath>

#include "glint/errors.h"
#include "glint/marches.h"
#include "glint/memory.h"
#include "glint/stages.h"
#include "look.h"
#include "march.h"
#include "parallel.h"
#include "raster.h"

namespace glint {
namespace {

inline bool finite4(const float* p) {
  return p[0] - p[0] == 0.0f && p[1] - p[1] == 0.0f && p[2] - p[2] == 0.0f && p[3] - p[3] == 0.0f;
}
inline float clamp01(float v) { return v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v); }

// A colour texel for sampling: non-finite values (an Inf sun, a NaN from a
// broken pass) read as black so that they cannot leave the core.
inline void texel_rgba(const Image& img, int x, int y, float out[4]) {
  const float* p = img.px(x, y);
  for (int c = 0; c < 4; ++c) out[c] = (p[c] - p[c] == 0.0f) ? p[c] : 0.0f;
}

// Bilinear sample with clamp-to-edge, as GL_LINEAR + GL_CLAMP_TO_EDGE does.
void sample_bilinear(const Image& img, float u, float v, float out[4]) {
  const float tx = u * static_cast<float>(img.width) - 0.5f;
  const float ty = v * static_cast<float>(img.height) - 0.5f;
  const float fx0 = std::floor(tx), fy0 = std::floor(ty);
  const float ax = tx - fx0, ay = ty - fy0;
  auto clampi = [](float f, int hi) {
    if (!(f >= 0.0f)) return 0;
    return f > static_cast<float>(hi) ? hi : static_cast<int>(f);
  };
  const int x0 = clampi(fx0, img.width - 1), x1 = clampi(fx0 + 1.0f, img.width - 1);
  const int y0 = clampi(fy0, img.height - 1), y1 = clampi(fy0 + 1.0f, img.height - 1);
  float a[4], b[4], c[4], d[4];
  texel_rgba(img, x0, y0, a);
  texel_rgba(img, x1, y0, b);
  texel_rgba(img, x0, y1, c);
  texel_rgba(img, x1, y1, d);
  for (int k = 0; k < 4; ++k) {
    const float bottom = a[k] * (1.0f - ax) + b[k] * ax;
    const float top = c[k] * (1.0f - ax) + d[k] * ax;
    out[k] = bottom * (1.0f - ay) + top * ay;
  }
}

// One tap of the blur along an axis: position p in texel units (integer p is
// a texel centre), linearly interpolated and clamped to the edge.
inline float tap_1d(const float* line, ptrdiff_t stride, int n, float p, int c) {
  const float f0 = std::floor(p);
  const float a = p - f0;
  int i0 = static_cast<int>(f0);
  int i1 = i0 + 1;
  i0 = std::clamp(i0, 0, n - 1);
  i1 = std::clamp(i1, 0, n - 1);
  const float v0 = line[i0 * stride + c], v1 = line[i1 * stride + c];
  return a == 0.0f ? v0 : v0 * (1.0f - a) + v1 * a;
}

// Box sums along one axis of 4-channel texels `stride` floats apart:
// sum over i = -size..size of tap(x + i * sep), for x in [begin, end), handed
// to emit(x, sum). Taps clamp to [0, n). With a whole-pixel separation k the
// window slides: going from x - k to x drops the tap at x - k - size * k and
// adds the one at x + size * k, so each residue class of x mod k keeps a
// running sum (in double, so sliding adds no drift) and the cost per texel no
// longer grows with the box. Other separations interpolate each tap.
template <class Emit>
void box_sums_1d(const float* line, ptrdiff_t stride, int n, int size, float sep, int begin, int end,
                 Emit&& emit) {
  float sum[4];
  if (sep != std::floor(sep)) {
    for (int x = begin; x < end; ++x) {
      for (int c = 0; c < 4; ++c) sum[c] = 0.0f;
      for (int i = -size; i <= size; ++i) {
        const float p = static_cast<float>(x) + static_cast<float>(i) * sep;
        for (int c = 0; c < 4; ++c) sum[c] += tap_1d(line, stride, n, p, c);
      }
      emit(x, sum);
    }
    return;
  }
  const long k = static_cast<long>(sep);
  auto at = [&](long i) { return line + std::clamp(i, 0L, static_cast<long>(n) - 1) * stride; };
  for (int first = begin; first < std::min<long>(end, begin + k); ++first) {
    double acc[4] = {0, 0, 0, 0};
    for (long i = -size; i <= size; ++i) {
      const float* t = at(first + i * k);
      for (int c = 0; c < 4; ++c) acc[c] += t[c];
    }
    for (long x = first;;) {
      for (int c = 0; c < 4; ++c) sum[c] = static_cast<float>(acc[c]);
      emit(static_cast<int>(x), sum);
      x += k;
      if (x >= end) break;
      const float* drop = at(x - k - size * k);
      const float* add = at(x + size * k);
      for (int c = 0; c < 4; ++c) acc[c] += static_cast<double>(add[c]) - drop[c];
    }
  }
}

class CpuBackend final : public Backend {
 public:
  explicit CpuBackend(int threads) : threads_(threads) {}
  std::string name() const override { return "cpu"; }

  Image trace(const TraceInputs& in, const TraceOptions& opt) override {
    require_trace_inputs(in, opt);
    require_trace_memory(in, opt, false);
    return march_info(opt.march).cpu(in, opt, threads_);
  }

  Image reflection_color(const Image& uv, const Image& color) override {
    require_image(uv, "uv");
    require_image(color, "color");
    Image out(uv.width, uv.height);
    parallel_rows(0, out.height, threads_, [&](int y) {
      for (int x = 0; x < out.width; ++x) {
        const float* t = uv.px(x, y);
        const float alpha = clamp01(t[2]);
        if (!(alpha > 0.0f) || !finite4(t)) continue;
        float c[4];
        sample_bilinear(color, t[0], t[1], c);
        float* o = out.px(x, y);
        o[0] = c[0] * alpha;
        o[1] = c[1] * alpha;
        o[2] = c[2] * alpha;
        o[3] = alpha;
      }
    });
    return out;
  }

  Image box_blur(const Image& src, const BlurOptions& opt, const int* region) override {
    require_image(src, "image");
    validate(opt);
    Image out = src;
    if (opt.size == 0) return out;
    int x0 = 0, y0 = 0, x1 = src.width, y1 = src.height;
    if (region) {
      x0 = std::max(0, region[0]);
      y0 = std::max(0, region[1]);
      x1 = std::min(src.width, region[2]);
      y1 = std::min(src.height, region[3]);
    }
    if (x0 >= x1 || y0 >= y1) return out;
    // Separable: clamp-to-edge and linear taps both factor per axis, so the
    // (2s+1)^2 box equals a horizontal pass followed by a vertical one.
    const int size = opt.size;
    const float sep = std::max(opt.separation, 1.0f);
    const int reach = static_cast<int>(std::ceil(size * sep)) + 1;
    const int hy0 = std::max(0, y0 - reach), hy1 = std::min(src.height, y1 + reach);
    const int w = x1 - x0;
    const ptrdiff_t hstride = static_cast<ptrdiff_t>(w) * 4;
    std::vector<float> horiz(static_cast<size_t>(hy1 - hy0) * w * 4);
    parallel_rows(hy0, hy1, threads_, [&](int y) {
      float* dst = horiz.data() + static_cast<size_t>(y - hy0) * hstride;
      box_sums_1d(src.px(0, y), 4, src.width, size, sep, x0, x1,
                  [&](int x, const float* sum) { std::copy(sum, sum + 4, dst + (x - x0) * 4); });
    });
    const float norm = 1.0f / static_cast<float>((2 * size + 1) * (2 * size + 1));
    // Vertical sums, handed out in blocks of columns. With a whole-pixel
    // separation the window slides down the block a row at a time, so reads
    // stream along rows instead of striding down 33 MB columns at 1080p.
    constexpr int kBlock = 64;
    const int blocks = (w + kBlock - 1) / kBlock;
    const bool sliding = sep == std::floor(sep);
    parallel_rows(0, blocks, threads_, [&](int b) {
      const int bx0 = x0 + b * kBlock, bx1 = std::min(x1, bx0 + kBlock);
      // Row r of the horizontal sums (absolute row, clamped to the image;
      // `reach` keeps every tap inside [hy0, hy1)).
      auto row = [&](long r) {
        r = std::clamp(r, 0L, static_cast<long>(src.height) - 1);
        return horiz.data() + (r - hy0) * hstride + static_cast<ptrdiff_t>(bx0 - x0) * 4;
      };
      if (!sliding) {
        for (int x = bx0; x < bx1; ++x) {
          const float* column = horiz.data() + static_cast<size_t>(x - x0) * 4 - hy0 * hstride;
          box_sums_1d(column, hstride, src.height, size, sep, y0, y1, [&](int y, const float* sum) {
            float* o = out.px(x, y);
            for (int c = 0; c < 4; ++c) o[c] = sum[c] * norm;
          });
        }
        return;
      }
      const long k = static_cast<long>(sep);
      const int n = (bx1 - bx0) * 4;
      std::vector<double> acc(n);
      for (long first = y0; first < std::min<long>(y1, y0 + k); ++first) {
        std::fill(acc.begin(), acc.end(), 0.0);
        for (long j = -size; j <= size; ++j) {
          const float* r = row(first + j * k);
          for (int i = 0; i < n; ++i) acc[i] += r[i];
        }
        for (long y = first;;) {
          float* o = out.px(bx0, static_cast<int>(y));
          for (int i = 0; i < n; ++i) o[i] = static_cast<float>(acc[i]) * norm;
          y += k;
          if (y >= y1) break;
          const float* drop = row(y - k - size * k);
          const float* add = row(y + size * k);
          for (int i = 0; i < n; ++i) acc[i] += static_cast<double>(add[i]) - drop[i];
        }
      }
    });
    return out;
  }

  Image specular_weight(const Image& position, const Image& normal, const Image& specular,
                        const Mat4& projection) override {
    require_specular_weight_inputs(position, normal, specular, projection);
    return cpu::specular_weight(position, normal, specular, projection, threads_);
  }

  Image cone_blur(const Image& color, const Image& uv, const Image& specular,
                  const MirrorScale* mirror) override {
    require_cone_blur_inputs(color, uv, specular, mirror);
    return cpu::cone_blur(color, uv, specular, mirror, threads_);
  }

  Image reflection(const Image& color, const Image* blurred, const Image& specular,
                   const Image* weight) override {
    require_reflection_inputs(color, blurred, specular, weight);
    Image out(color.width, color.height);
    parallel_rows(0, out.height, threads_, [&](int y) {
      for (int x = 0; x < out.width; ++x) {
        const float* s = specular.px(x, y);
        if (!is_reflective(s)) continue;
        const float* c = color.px(x, y);
        float* o = out.px(x, y);
        float mixed[4];
        if (blurred) {
          const float roughness = roughness_of(s);
          const float* b = blurred->px(x, y);
          for (int k = 0; k < 4; ++k) mixed[k] = c[k] * (1.0f - roughness) + b[k] * roughness;
        } else {
          std::copy(c, c + 4, mixed);
        }
        if (weight) {
          const float* wt = weight->px(x, y);
          for (int k = 0; k < 4; ++k) o[k] = mixed[k] * wt[k];
        } else {
          const float amount = specular_amount(s);
          for (int k = 0; k < 4; ++k) o[k] = mixed[k] * amount;
        }
      }
    });
    return out;
  }

  Image combine(const Image& base, const Image& reflection, Combine mode, const Image* specular_base,
                const Image* coverage) override {
    require_combine_inputs(base, reflection, mode, specular_base, coverage);
    Image out(base.width, base.height);
    parallel_rows(0, out.height, threads_, [&](int y) {
      for (int x = 0; x < out.width; ++x) {
        const float* b = base.px(x, y);
        const float* r = reflection.px(x, y);
        float* o = out.px(x, y);
        if (specular_base) {
          // Replace, do not add: the engine's specular goes where the trace
          // found what it stood in for.
          const float* sb = specular_base->px(x, y);
          const float cov = clamp01(coverage->px(x, y)[3]);
          for (int k = 0; k < 3; ++k) o[k] = std::max(b[k] - sb[k] * cov, 0.0f) + r[k];
          o[3] = b[3];
          continue;
        }
        const float a = clamp01(r[3]);
        for (int k = 0; k < 3; ++k) {
          o[k] = mode == Combine::Over ? b[k] * (1.0f - a) + r[k] : b[k] * (1.0f - a) + r[k] * a;
        }
        o[3] = b[3];
      }
    });
    return out;
  }

  GBufferImages rasterize(const RasterInputs& in) override { return cpu::rasterize(in, threads_); }

 private:
  int threads_;
};

}  // namespace

std::unique_ptr<Backend> make_cpu_backend(int threads) {
  return std::make_unique<CpuBackend>(threads);
}

}  // namespace glint
