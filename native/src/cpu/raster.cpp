// The CPU reference rasterizer: G-buffers from a view-space triangle soup.
//
// Coverage and attributes are decided separately, each the exact way:
// - Coverage: each triangle is clipped to the view volume in clip space,
//   projected, snapped to a 1/256-pixel grid and split into a fan; a pixel
//   centre is covered when all three integer edge functions pass the
//   top-left tie rule. Integer edge functions are exact, so an edge shared by
//   two triangles gives the same value (negated) to both and a centre on it
//   goes to exactly one of them.
// - Attributes: the pixel's ray is intersected with the unclipped, unsnapped
//   triangle in double precision (homogeneous barycentrics, which are the
//   perspective-correct ones), so positions lie on the exact ray and plane.
//
// Triangles are set up (clip, snap) and binned into bands of rows in
// parallel, then each band is rasterized into a depth + triangle-id buffer;
// shading reads only the winning triangle of each pixel (normals, normal
// maps, material), so overdraw costs only the depth test. Up to one chunk of
// triangles (the usual frame), a thread finishes a band at once (front test,
// back-face test, shading) in a band-sized buffer; more than that goes chunk
// by chunk (bounded memory for any count) into frame-sized buffers.
#include "raster.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>

#include "glint/errors.h"
#include "glint/memory.h"
#include "glint/stages.h"
#include "parallel.h"

namespace glint::cpu {
namespace {

// Sub-pixel precision of snapped vertices, as GL implementations snap.
constexpr int kSubBits = 8;
constexpr int64_t kSub = int64_t{1} << kSubBits;
constexpr int64_t kHalf = kSub / 2;  // a pixel centre's offset in sub-pixel units
constexpr size_t kChunk = size_t{1} << 16;

struct Clip {
  double x, y, z, w;
};

Clip to_clip(const Mat4& p, const float* v) {
  const double x = v[0], y = v[1], z = v[2];
  return {p(0, 0) * x + p(0, 1) * y + p(0, 2) * z + p(0, 3),
          p(1, 0) * x + p(1, 1) * y + p(1, 2) * z + p(1, 3),
          p(2, 0) * x + p(2, 1) * y + p(2, 2) * z + p(2, 3),
          p(3, 0) * x + p(3, 1) * y + p(3, 2) * z + p(3, 3)};
}

// Signed distance to clip plane k (inside when >= 0): near and far first, as
// they decide what exists at all; then the sides, which only bound the
// snapped coordinates to the image.
inline double plane_distance(const Clip& v, int k) {
  switch (k) {
    case 0: return v.w + v.z;
    case 1: return v.w - v.z;
    case 2: return v.w + v.x;
    case 3: return v.w - v.x;
    case 4: return v.w + v.y;
    default: return v.w - v.y;
  }
}

inline unsigned outcode(const Clip& v) {
  unsigned code = 0;
  for (int k = 0; k < 6; ++k)
    if (!(plane_distance(v, k) >= 0.0)) code |= 1u << k;
  return code;
}

// Sutherland-Hodgman against the planes in `planes`. The crossing point of
// an edge is always computed from its inside end toward its outside end, so
// two triangles sharing an edge (walking it in opposite directions) create
// bit-identical vertices and stay watertight after clipping.
int clip_polygon(Clip* poly, int n, unsigned planes) {
  Clip tmp[12];
  for (int k = 0; k < 6 && n > 0; ++k) {
    if (!(planes & (1u << k))) continue;
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const Clip& a = poly[i];
      const Clip& b = poly[(i + 1) % n];
      const double da = plane_distance(a, k), db = plane_distance(b, k);
      const bool ain = da >= 0.0, bin = db >= 0.0;
      if (ain) tmp[m++] = a;
      if (ain != bin) {
        const Clip& in = ain ? a : b;
        const Clip& out = ain ? b : a;
        const double din = ain ? da : db, dout = ain ? db : da;
        const double t = din / (din - dout);
        tmp[m++] = {in.x + t * (out.x - in.x), in.y + t * (out.y - in.y),
                    in.z + t * (out.z - in.z), in.w + t * (out.w - in.w)};
      }
    }
    n = m;
    std::copy(tmp, tmp + n, poly);
  }
  return n;
}

inline int64_t floor_div(int64_t a, int64_t b) {  // b > 0
  const int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}
inline int64_t ceil_div(int64_t a, int64_t b) { return -floor_div(-a, b); }

// One counter-clockwise (y up) screen triangle in sub-pixel units, with the
// pixel rectangle its centres can fall in.
struct ScreenTri {
  int32_t x[3], y[3];
  int32_t tri;  // index of the source triangle
  int32_t i_lo, i_hi, j_lo, j_hi;
};

// Calls span(j, i0, i1) for each row j in [j0, j1] with the inclusive run of
// covered pixel columns. Edge function of a->b at p: (b - a) x (p - a), > 0
// inside a CCW (y up) triangle. Ties (== 0) follow the top-left rule taken
// in image-index order, where "top" is the smaller row index: a left edge
// (inside to its right, dy < 0) and a horizontal edge with the inside at
// larger rows (dx > 0) keep their centres. Row 0 being the bottom of the
// picture, that is the picture's bottom edge; it is what Mesa (llvmpipe)
// does when drawing into a framebuffer object, so the GL backend agrees.
template <class Span>
void for_each_span(const ScreenTri& t, int j0, int j1, Span&& span) {
  int64_t dx[3], dy[3], ax[3], ay[3], thr[3];
  for (int e = 0; e < 3; ++e) {
    const int a = e, b = (e + 1) % 3;
    ax[e] = t.x[a];
    ay[e] = t.y[a];
    dx[e] = int64_t{t.x[b]} - t.x[a];
    dy[e] = int64_t{t.y[b]} - t.y[a];
    const bool top_left = dy[e] < 0 || (dy[e] == 0 && dx[e] > 0);
    thr[e] = top_left ? 0 : 1;  // E >= thr, E an integer
  }
  // Narrow triangles (most of a dense mesh) test each pixel of the row with
  // incremental edge values; wide ones solve each edge for its bound, which
  // costs divisions but no work per uncovered pixel. Both are exact, so they
  // give the same pixels.
  const bool narrow = t.i_hi - t.i_lo < 24;
  for (int j = j0; j <= j1; ++j) {
    const int64_t py = int64_t{j} * kSub + kHalf;
    if (narrow) {
      int64_t e[3], step[3];
      for (int k = 0; k < 3; ++k) {
        step[k] = -dy[k] * kSub;
        e[k] = dx[k] * (py - ay[k]) - dy[k] * (int64_t{t.i_lo} * kSub + kHalf - ax[k]) - thr[k];
      }
      int lo = -1, hi = -2;
      for (int i = t.i_lo; i <= t.i_hi; ++i) {
        if ((e[0] | e[1] | e[2]) >= 0) {  // all three >= 0
          if (lo < 0) lo = i;
          hi = i;
        } else if (lo >= 0) {
          break;  // convex: the run has ended
        }
        for (int k = 0; k < 3; ++k) e[k] += step[k];
      }
      if (lo >= 0) span(j, lo, hi);
      continue;
    }
    int64_t lo = t.i_lo, hi = t.i_hi;
    for (int e = 0; e < 3 && lo <= hi; ++e) {
      // E(i) = k + s * i with the centre px = i * kSub + kHalf.
      const int64_t k = dx[e] * (py - ay[e]) - dy[e] * (kHalf - ax[e]);
      const int64_t s = -dy[e] * kSub;
      if (s > 0) {
        lo = std::max(lo, ceil_div(thr[e] - k, s));
      } else if (s < 0) {
        hi = std::min(hi, floor_div(k - thr[e], -s));
      } else if (k < thr[e]) {
        hi = lo - 1;
      }
    }
    if (lo <= hi) span(j, static_cast<int>(lo), static_cast<int>(hi));
  }
}

// Clips, projects and snaps source triangle `tri`; appends its covering
// screen triangles (none when it misses every pixel centre) to `out`.
void setup_triangle(const float* corners, const Mat4& proj, int width, int height, int32_t tri,
                    std::vector<ScreenTri>& out) {
  for (int k = 0; k < 9; ++k)
    if (!std::isfinite(corners[k])) return;  // data, not an error: the triangle is skipped
  Clip poly[12];
  unsigned any = 0, all = 0x3f;
  for (int k = 0; k < 3; ++k) {
    poly[k] = to_clip(proj, corners + 3 * k);
    const unsigned c = outcode(poly[k]);
    any |= c;
    all &= c;
  }
  if (all) return;  // every corner outside one plane: nothing of it is in view
  const int n = any ? clip_polygon(poly, 3, any) : 3;
  if (n < 3) return;
  int32_t sx[12], sy[12];
  const double half_w = 0.5 * static_cast<double>(width) * kSub;
  const double half_h = 0.5 * static_cast<double>(height) * kSub;
  for (int k = 0; k < n; ++k) {
    const Clip& v = poly[k];
    if (!(v.w > 0.0)) return;  // only a degenerate projection gets here
    const double fx = (v.x / v.w + 1.0) * half_w, fy = (v.y / v.w + 1.0) * half_h;
    if (!(std::fabs(fx) < 1e9 && std::fabs(fy) < 1e9)) return;
    sx[k] = static_cast<int32_t>(std::llround(fx));
    sy[k] = static_cast<int32_t>(std::llround(fy));
  }
  for (int k = 1; k + 1 < n; ++k) {
    ScreenTri t;
    t.x[0] = sx[0], t.y[0] = sy[0];
    t.x[1] = sx[k], t.y[1] = sy[k];
    t.x[2] = sx[k + 1], t.y[2] = sy[k + 1];
    const int64_t area2 = (int64_t{t.x[1]} - t.x[0]) * (int64_t{t.y[2]} - t.y[0]) -
                          (int64_t{t.x[2]} - t.x[0]) * (int64_t{t.y[1]} - t.y[0]);
    if (area2 == 0) continue;
    if (area2 < 0) {
      std::swap(t.x[1], t.x[2]);
      std::swap(t.y[1], t.y[2]);
    }
    const int64_t xmin = std::min({t.x[0], t.x[1], t.x[2]}), xmax = std::max({t.x[0], t.x[1], t.x[2]});
    const int64_t ymin = std::min({t.y[0], t.y[1], t.y[2]}), ymax = std::max({t.y[0], t.y[1], t.y[2]});
    const int64_t i_lo = std::max<int64_t>(0, ceil_div(xmin - kHalf, kSub));
    const int64_t i_hi = std::min<int64_t>(width - 1, floor_div(xmax - kHalf, kSub));
    const int64_t j_lo = std::max<int64_t>(0, ceil_div(ymin - kHalf, kSub));
    const int64_t j_hi = std::min<int64_t>(height - 1, floor_div(ymax - kHalf, kSub));
    if (i_lo > i_hi || j_lo > j_hi) continue;  // falls between pixel centres
    t.tri = tri;
    t.i_lo = static_cast<int32_t>(i_lo), t.i_hi = static_cast<int32_t>(i_hi);
    t.j_lo = static_cast<int32_t>(j_lo), t.j_hi = static_cast<int32_t>(j_hi);
    out.push_back(t);
  }
}

// The pixel ray against the unclipped triangle. With clip-space corners
// c_k = (x, y, w), the point of the triangle seen at ndc (x, y) has
// barycentrics proportional to u_k = (c_{k+1} x c_{k+2}) . (x, y, 1); those
// are perspective-correct by construction. det = c_0 . (c_1 x c_2) has the
// sign of the triangle's screen-space area (for the part in front of the
// eye), which is what decides front and back faces.
struct TriPlane {
  double e[3][3];
  double z[3];  // view-space z of the corners
  bool back;
};

bool make_plane(const float* corners, const Mat4& proj, TriPlane& pl) {
  double c[3][3];
  for (int k = 0; k < 3; ++k) {
    const Clip v = to_clip(proj, corners + 3 * k);
    c[k][0] = v.x, c[k][1] = v.y, c[k][2] = v.w;
    pl.z[k] = corners[3 * k + 2];
  }
  for (int k = 0; k < 3; ++k) {
    const double* a = c[(k + 1) % 3];
    const double* b = c[(k + 2) % 3];
    pl.e[k][0] = a[1] * b[2] - a[2] * b[1];
    pl.e[k][1] = a[2] * b[0] - a[0] * b[2];
    pl.e[k][2] = a[0] * b[1] - a[1] * b[0];
  }
  const double det = c[0][0] * pl.e[0][0] + c[0][1] * pl.e[0][1] + c[0][2] * pl.e[0][2];
  if (!(det != 0.0) || !std::isfinite(det)) return false;
  pl.back = det < 0.0;
  return true;
}

// Barycentrics at the centre of pixel (i, j), clamped onto the triangle:
// only pixels that snapping let in fall outside it, and clamping keeps a
// nearly edge-on triangle from extrapolating far off its surface.
inline bool barycentric(const TriPlane& pl, int i, int j, double inv_w2, double inv_h2,
                        double b[3]) {
  const double x = (2.0 * i + 1.0) * inv_w2 - 1.0;
  const double y = (2.0 * j + 1.0) * inv_h2 - 1.0;
  double u[3];
  for (int k = 0; k < 3; ++k) u[k] = pl.e[k][0] * x + pl.e[k][1] * y + pl.e[k][2];
  const double inv = 1.0 / (u[0] + u[1] + u[2]);
  b[0] = u[0] * inv, b[1] = u[1] * inv, b[2] = u[2] * inv;
  if (b[0] >= 0.0 && b[1] >= 0.0 && b[2] >= 0.0 && b[0] <= 1.0 && b[1] <= 1.0 && b[2] <= 1.0)
    return true;  // the usual case: the centre is on the triangle
  if (!std::isfinite(inv)) return false;
  double total = 0.0;
  for (int k = 0; k < 3; ++k) {
    b[k] = b[k] > 0.0 ? (b[k] < 1.0 ? b[k] : 1.0) : 0.0;  // NaN -> 0
    total += b[k];
  }
  if (!(total > 0.0)) return false;
  for (int k = 0; k < 3; ++k) b[k] /= total;
  return true;
}

struct Vec3 {
  double x, y, z;
};
inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator*(Vec3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
// Unit vector, or false when v is zero or not finite.
inline bool normalize(Vec3& v) {
  const double len = std::sqrt(dot(v, v));
  if (!(len > 1e-30) || !std::isfinite(len)) return false;
  v = v * (1.0 / len);
  return true;
}
inline Vec3 interp3(const float* base, int stride, const double b[3]) {
  Vec3 r{0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    const float* p = base + k * stride;
    r = r + Vec3{p[0], p[1], p[2]} * b[k];
  }
  return r;
}

// Bilinear, wrapping (GL_REPEAT), texel (0, 0) at uv (0, 0) = bottom-left.
bool sample_normal_map(const Image& img, double u, double v, Vec3& rgb) {
  if (!std::isfinite(u) || !std::isfinite(v)) return false;
  u -= std::floor(u);
  v -= std::floor(v);
  const double tx = u * img.width - 0.5, ty = v * img.height - 0.5;
  const double fx = std::floor(tx), fy = std::floor(ty);
  const double ax = tx - fx, ay = ty - fy;
  auto wrap = [](long long i, int n) { return static_cast<int>(((i % n) + n) % n); };
  const int x0 = wrap(static_cast<long long>(fx), img.width);
  const int x1 = wrap(static_cast<long long>(fx) + 1, img.width);
  const int y0 = wrap(static_cast<long long>(fy), img.height);
  const int y1 = wrap(static_cast<long long>(fy) + 1, img.height);
  const float* p00 = img.px(x0, y0);
  const float* p10 = img.px(x1, y0);
  const float* p01 = img.px(x0, y1);
  const float* p11 = img.px(x1, y1);
  double c[3];
  for (int k = 0; k < 3; ++k) {
    const double bottom = p00[k] * (1.0 - ax) + p10[k] * ax;
    const double top = p01[k] * (1.0 - ax) + p11[k] * ax;
    c[k] = bottom * (1.0 - ay) + top * ay;
  }
  rgb = {c[0], c[1], c[2]};
  return std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]);
}

// The tangent-space normal map applied to unit normal n (unflipped).
// Anything degenerate (no usable uv, tangent parallel to n, a NaN texel)
// leaves n as it is.
Vec3 apply_normal_map(const RasterInputs& in, const Image& map, size_t tri, const double b[3],
                      Vec3 n) {
  const float* uv = in.mesh.uvs.data() + tri * 6;
  const double u = uv[0] * b[0] + uv[2] * b[1] + uv[4] * b[2];
  const double v = uv[1] * b[0] + uv[3] * b[1] + uv[5] * b[2];
  Vec3 rgb;
  if (!sample_normal_map(map, u, v, rgb)) return n;
  const Vec3 nt = rgb * 2.0 - Vec3{1.0, 1.0, 1.0};
  const float* tg = in.mesh.tangents.data() + tri * 12;
  Vec3 t = interp3(tg, 4, b);
  const double w = tg[3] * b[0] + tg[7] * b[1] + tg[11] * b[2];
  t = t - n * dot(n, t);
  if (!normalize(t)) return n;
  const Vec3 bt = cross(n, t) * (w < 0.0 ? -1.0 : 1.0);  // Blender: tangent.w is the bitangent sign
  Vec3 r = t * nt.x + bt * nt.y + n * nt.z;
  return normalize(r) ? r : n;
}

}  // namespace

namespace {

// One chunk of triangles, set up and binned into bands of rows.
struct Chunk {
  struct Slice {
    std::vector<ScreenTri> tris;
    std::vector<std::vector<uint32_t>> bins;  // per band: indices into tris, in triangle order
  };
  size_t begin = 0;
  std::vector<TriPlane> planes;  // per triangle of the chunk (valid where it has screen triangles)
  std::vector<Slice> slices;
};

// The depth-test state of a run of rows, each pointer at the run's first row.
struct DepthRows {
  double* depth;
  int32_t* winner;
  double* back_depth;  // null without the back layer
  int32_t* back_winner;
};

class Rasterizer {
 public:
  Rasterizer(const RasterInputs& in, int threads)
      : in_(in),
        threads_(threads),
        width_(in.width),
        height_(in.height),
        band_rows_(std::max(8, (in.height + 255) / 256)),
        bands_((in.height + band_rows_ - 1) / band_rows_),
        inv_w2_(1.0 / in.width),
        inv_h2_(1.0 / in.height) {}

  GBufferImages run();

 private:
  void setup_chunk(size_t begin, Chunk& c) const;
  // The depth tests of the band's rows against the chunk's triangles.
  void front_band(const Chunk& c, int band, const DepthRows& rows) const;
  void back_band(const Chunk& c, int band, const DepthRows& rows) const;
  // Writes the G-buffers of the band's pixels from the winners. With `planes`
  // (the whole mesh in one chunk) a winner's plane is looked up, not rebuilt.
  void shade_band(int band, const DepthRows& rows, const std::vector<TriPlane>* planes);
  void clear_rows(const DepthRows& rows, size_t n) const;

  // The images this call writes: position, normal, specular, then with the
  // back layer back_position, and with its albedo back_albedo.
  int output_count() const { return in_.back_layer ? (in_.back_albedo ? 5 : 4) : 3; }
  Image& output(int k) {
    Image* images[5] = {&out_.position, &out_.normal, &out_.specular, &out_.back_position, &out_.back_albedo};
    return *images[k];
  }

  int row0(int band) const { return band * band_rows_; }
  int row1(int band) const { return std::min(height_, row0(band) + band_rows_) - 1; }

  const RasterInputs& in_;
  const int threads_;
  const int width_, height_, band_rows_, bands_;
  const double inv_w2_, inv_h2_;
  GBufferImages out_;
};

void Rasterizer::setup_chunk(size_t begin, Chunk& c) const {
  const Mesh& mesh = in_.mesh;
  const size_t n = std::min(kChunk, mesh.triangle_count() - begin);
  c.begin = begin;
  c.planes.resize(n);
  // Slices are contiguous runs of triangles so that walking them in order
  // keeps submission order, which makes depth ties deterministic.
  const int slices = static_cast<int>(std::min<size_t>((n + 1023) / 1024, size_t(resolve_threads(threads_)) * 4));
  c.slices.assign(slices, {});
  auto setup_slice = [&](int s) {
    const size_t a = n * s / slices, b = n * (s + 1) / slices;
    Chunk::Slice& sl = c.slices[s];
    sl.bins.assign(bands_, {});
    for (size_t k = a; k < b; ++k) {
      const size_t tri = begin + k;
      const float* corners = mesh.positions.data() + tri * 9;
      const size_t first = sl.tris.size();
      setup_triangle(corners, in_.projection, width_, height_, static_cast<int32_t>(tri), sl.tris);
      if (sl.tris.size() == first) continue;
      if (!make_plane(corners, in_.projection, c.planes[k])) {
        sl.tris.resize(first);  // seen edge-on through the eye: covers nothing
        continue;
      }
      for (size_t q = first; q < sl.tris.size(); ++q) {
        const ScreenTri& t = sl.tris[q];
        for (int band = t.j_lo / band_rows_; band <= t.j_hi / band_rows_; ++band)
          sl.bins[band].push_back(static_cast<uint32_t>(q));
      }
    }
  };
  parallel_rows(0, slices, threads_, setup_slice);  // binning allocates: failures come back here
}

// Each covered pixel centre of the band: a depth test on the view distance,
// the smaller wins (ties: the earlier triangle, walked first).
void Rasterizer::front_band(const Chunk& c, int band, const DepthRows& rows) const {
  const int r0 = row0(band), r1 = row1(band);
  for (const Chunk::Slice& sl : c.slices) {
    for (uint32_t q : sl.bins[band]) {
      const ScreenTri& t = sl.tris[q];
      const TriPlane& pl = c.planes[t.tri - c.begin];
      for_each_span(t, std::max(t.j_lo, r0), std::min(t.j_hi, r1), [&](int j, int i0, int i1) {
        const size_t row = static_cast<size_t>(j - r0) * width_;
        for (int i = i0; i <= i1; ++i) {
          double b[3];
          if (!barycentric(pl, i, j, inv_w2_, inv_h2_, b)) continue;
          const double d = -(b[0] * pl.z[0] + b[1] * pl.z[1] + b[2] * pl.z[2]);
          if (d < rows.depth[row + i]) {
            rows.depth[row + i] = d;
            rows.winner[row + i] = t.tri;
          }
        }
      });
    }
  }
}

// The back-face layer: the nearest back-facing triangle strictly behind each
// pixel's front surface (a closed object's far side), which is what tells a
// march how thick the object in front really is. Front faces and pixels with
// no front surface are rejected before any barycentric is computed.
void Rasterizer::back_band(const Chunk& c, int band, const DepthRows& rows) const {
  const int r0 = row0(band), r1 = row1(band);
  for (const Chunk::Slice& sl : c.slices) {
    for (uint32_t q : sl.bins[band]) {
      const ScreenTri& t = sl.tris[q];
      const TriPlane& pl = c.planes[t.tri - c.begin];
      if (!pl.back) continue;
      for_each_span(t, std::max(t.j_lo, r0), std::min(t.j_hi, r1), [&](int j, int i0, int i1) {
        const size_t row = static_cast<size_t>(j - r0) * width_;
        for (int i = i0; i <= i1; ++i) {
          const size_t px = row + i;
          if (rows.winner[px] < 0) continue;
          double b[3];
          if (!barycentric(pl, i, j, inv_w2_, inv_h2_, b)) continue;
          const double d = -(b[0] * pl.z[0] + b[1] * pl.z[1] + b[2] * pl.z[2]);
          const double front = rows.depth[px];
          if (d > front + kBackSeparation * std::fabs(front) && d < rows.back_depth[px]) {
            rows.back_depth[px] = d;
            rows.back_winner[px] = t.tri;
          }
        }
      });
    }
  }
}

void Rasterizer::clear_rows(const DepthRows& rows, size_t n) const {
  std::fill(rows.depth, rows.depth + n, std::numeric_limits<double>::infinity());
  std::fill(rows.winner, rows.winner + n, -1);
  if (rows.back_depth) {
    std::fill(rows.back_depth, rows.back_depth + n, std::numeric_limits<double>::infinity());
    std::fill(rows.back_winner, rows.back_winner + n, -1);
  }
}

void Rasterizer::shade_band(int band, const DepthRows& rows, const std::vector<TriPlane>* planes) {
  const Mesh& mesh = in_.mesh;
  const Mat4& proj = in_.projection;
  const int r0 = row0(band), r1 = row1(band);
  // Neighbours usually share a triangle: reuse its plane.
  auto plane_for = [&](int32_t id, TriPlane& cache, int32_t& cached) -> const TriPlane* {
    if (planes) return &(*planes)[static_cast<size_t>(id)];
    if (id != cached) {
      if (!make_plane(mesh.positions.data() + static_cast<size_t>(id) * 9, proj, cache))
        return nullptr;  // cannot fail for a winner
      cached = id;
    }
    return &cache;
  };
  const size_t row_floats = static_cast<size_t>(width_) * 4;
  for (int j = r0; j <= r1; ++j) {
    // Every texel a row's loops skip stays 0 (run() leaves the outputs unset).
    for (int k = 0; k < output_count(); ++k) std::fill(output(k).px(0, j), output(k).px(0, j) + row_floats, 0.0f);
    const int32_t* win = rows.winner + static_cast<size_t>(j - r0) * width_;
    TriPlane cache;
    int32_t cached = -1;
    for (int i = 0; i < width_; ++i) {
      const int32_t id = win[i];
      if (id < 0) continue;
      const size_t tri = static_cast<size_t>(id);
      const float* corners = mesh.positions.data() + tri * 9;
      const TriPlane* pl = plane_for(id, cache, cached);
      double b[3];
      if (!pl || !barycentric(*pl, i, j, inv_w2_, inv_h2_, b)) continue;
      const Vec3 p = interp3(corners, 3, b);
      Vec3 n = interp3(mesh.normals.data() + tri * 9, 3, b);
      if (!normalize(n)) {
        // Zero or non-finite corner normals: fall back to the face normal,
        // which faces the eye on a front face like a sane corner normal would.
        const Vec3 p0{corners[0], corners[1], corners[2]};
        const Vec3 p1{corners[3], corners[4], corners[5]};
        const Vec3 p2{corners[6], corners[7], corners[8]};
        n = cross(p1 - p0, p2 - p0);
        if (!normalize(n)) continue;
      }
      const Material& mat = in_.materials[mesh.material[tri]];
      if (mat.normal_map >= 0) n = apply_normal_map(in_, in_.normal_maps[mat.normal_map], tri, b, n);
      if (pl->back) n = n * -1.0;
      float* po = out_.position.px(i, j);
      po[0] = static_cast<float>(p.x);
      po[1] = static_cast<float>(p.y);
      po[2] = static_cast<float>(p.z);
      po[3] = 1.0f;
      float* no = out_.normal.px(i, j);
      no[0] = static_cast<float>(n.x);
      no[1] = static_cast<float>(n.y);
      no[2] = static_cast<float>(n.z);
      no[3] = 1.0f;
      float* so = out_.specular.px(i, j);
      so[0] = mat.specular[0];
      so[1] = mat.specular[1];
      so[2] = mat.specular[2];
      so[3] = shininess_to_alpha(mat.shininess);
    }
    if (!rows.back_winner) continue;
    const int32_t* back = rows.back_winner + static_cast<size_t>(j - r0) * width_;
    cached = -1;
    for (int i = 0; i < width_; ++i) {
      const int32_t id = back[i];
      if (id < 0) continue;
      const float* corners = mesh.positions.data() + static_cast<size_t>(id) * 9;
      const TriPlane* pl = plane_for(id, cache, cached);
      double b[3];
      if (!pl || !barycentric(*pl, i, j, inv_w2_, inv_h2_, b)) continue;
      const Vec3 p = interp3(corners, 3, b);
      float* po = out_.back_position.px(i, j);
      po[0] = static_cast<float>(p.x);
      po[1] = static_cast<float>(p.y);
      po[2] = static_cast<float>(p.z);
      po[3] = 1.0f;
      if (!in_.back_albedo) continue;
      // The same winner's material: a reflection that meets this hidden side
      // is shaded with its own colour, not the front texel's.
      const float* albedo = in_.materials[mesh.material[static_cast<size_t>(id)]].albedo;
      float* ao = out_.back_albedo.px(i, j);
      ao[0] = albedo[0];
      ao[1] = albedo[1];
      ao[2] = albedo[2];
      ao[3] = 1.0f;
    }
  }
}

GBufferImages Rasterizer::run() {
  const bool back = in_.back_layer;
  const size_t count = in_.mesh.triangle_count();
  // The outputs are most of the memory a call touches (33 MB each at
  // 1920x1080; the buffer pool keeps them mapped between frames). shade_band()
  // zeroes each row just before it shades it, while the row is in the cache:
  // zeroed whole up front, every covered texel was written twice.
  for (int k = 0; k < output_count(); ++k) output(k) = Image::uninitialized(width_, height_);

  if (count <= kChunk) {
    // The usual case: every triangle set up at once, so each band can be
    // finished (front test, back test, shading) while its rows are in cache,
    // with depth buffers of one band per thread instead of the whole frame.
    Chunk c;
    setup_chunk(0, c);
    const size_t band_px = static_cast<size_t>(band_rows_) * width_;
    std::atomic<int> next{0};
    parallel_rows(0, resolve_threads(threads_), threads_, [&](int) {
      std::vector<double> depth(band_px), back_depth(back ? band_px : 0);
      std::vector<int32_t> winner(band_px), back_winner(back ? band_px : 0);
      const DepthRows rows{depth.data(), winner.data(), back ? back_depth.data() : nullptr,
                           back ? back_winner.data() : nullptr};
      for (int band = next.fetch_add(1); band < bands_; band = next.fetch_add(1)) {
        clear_rows(rows, static_cast<size_t>(row1(band) - row0(band) + 1) * width_);
        front_band(c, band, rows);
        if (back) back_band(c, band, rows);
        shade_band(band, rows, &c.planes);
      }
    });
    return std::move(out_);
  }

  // Many triangles: chunks keep the set-up's memory bounded, so the depth
  // buffers span the frame and the back test needs a second round of chunks
  // (it compares against the final front depth).
  const size_t pixels = static_cast<size_t>(width_) * height_;
  std::vector<double> depth(pixels), back_depth(back ? pixels : 0);
  std::vector<int32_t> winner(pixels), back_winner(back ? pixels : 0);
  auto rows_of = [&](int band) {
    const size_t at = static_cast<size_t>(row0(band)) * width_;
    return DepthRows{depth.data() + at, winner.data() + at, back ? back_depth.data() + at : nullptr,
                     back ? back_winner.data() + at : nullptr};
  };
  parallel_rows(0, bands_, threads_, [&](int band) {
    clear_rows(rows_of(band), static_cast<size_t>(row1(band) - row0(band) + 1) * width_);
  });
  Chunk c;
  for (size_t begin = 0; begin < count; begin += kChunk) {
    setup_chunk(begin, c);
    parallel_rows(0, bands_, threads_, [&](int band) { front_band(c, band, rows_of(band)); });
  }
  if (back) {
    for (size_t begin = 0; begin < count; begin += kChunk) {
      setup_chunk(begin, c);
      parallel_rows(0, bands_, threads_, [&](int band) { back_band(c, band, rows_of(band)); });
    }
  }
  parallel_rows(0, bands_, threads_, [&](int band) { shade_band(band, rows_of(band), nullptr); });
  return std::move(out_);
}

}  // namespace

GBufferImages rasterize(const RasterInputs& in, int threads) {
  validate(in);
  require_raster_memory(in, false);
  return Rasterizer(in, threads).run();
}

std::vector<int> coverage_count(const std::vector<float>& positions, const Mat4& projection,
                                int width, int height) {
  if (positions.size() % 9 != 0) throw InvalidArgument("positions", "expected 9 floats per triangle");
  if (width < 1 || height < 1 || width > kMaxImageSide || height > kMaxImageSide)
    throw InvalidArgument("width", "expected a size in 1.." + std::to_string(kMaxImageSide));
  validate_projection(projection);
  std::vector<int> counts(static_cast<size_t>(width) * height, 0);
  std::vector<ScreenTri> tris;
  for (size_t tri = 0; tri < positions.size() / 9; ++tri) {
    tris.clear();
    TriPlane pl;
    if (!make_plane(positions.data() + tri * 9, projection, pl)) continue;
    setup_triangle(positions.data() + tri * 9, projection, width, height,
                   static_cast<int32_t>(tri), tris);
    for (const ScreenTri& t : tris)
      for_each_span(t, t.j_lo, t.j_hi, [&](int j, int i0, int i1) {
        for (int i = i0; i <= i1; ++i) ++counts[static_cast<size_t>(j) * width + i];
      });
  }
  return counts;
}

}  // namespace glint::cpu
