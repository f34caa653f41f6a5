// march="exact": every pixel's mirror ray traced against the scene's own
// triangles with Embree (3 or 4, whichever the distribution has), the answer
// every screen-space march approximates, and the ExactScene that keeps its
// BVH between calls (glint/exact_scene.h). Embree appears in no other file.
// The rules (docs/marches.md, "The exact march"): the first hit within
// max_distance, reported as (u, v, 1, 1) only where the camera sees that
// point; no fades.
#if GLINT_EMBREE_MAJOR >= 4
#include <embree4/rtcore.h>
#else
#include <embree3/rtcore.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <vector>

#include "cpu/outline.h"
#include "cpu/ray.h"
#include "exact.h"
#include "glint/errors.h"
#include "glint/exact_scene.h"
#include "glint/mesh.h"
#include "parallel.h"

namespace glint {
namespace {

using cpu::MarchSetup;
using cpu::V3;

struct D3 {
  double x, y, z;
};
D3 d3(V3 v) { return {v.x, v.y, v.z}; }
D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 operator*(D3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double norm(D3 a) { return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }

// Embree reports errors through a callback, from whichever thread met them;
// the first one becomes the exception the caller sees.
class ErrorSink {
 public:
  void record(RTCError code, const char* what) {
    std::lock_guard<std::mutex> lock(mu_);
    if (first_.empty()) first_ = "Embree error " + std::to_string(code) + ": " + (what ? what : "");
  }
  // Throws the first error recorded since the last call, if any.
  void rethrow() {
    std::lock_guard<std::mutex> lock(mu_);
    if (first_.empty()) return;
    std::string e;
    e.swap(first_);
    throw Error("glint: march \"exact\": " + e);
  }

 private:
  std::mutex mu_;
  std::string first_;
};

void on_device_error(void* user, RTCError code, const char* what) {
  static_cast<ErrorSink*>(user)->record(code, what);
}

struct DeviceDeleter {
  void operator()(RTCDevice d) const { rtcReleaseDevice(d); }
};
struct SceneDeleter {
  void operator()(RTCScene s) const { rtcReleaseScene(s); }
};
struct GeometryDeleter {
  void operator()(RTCGeometry g) const { rtcReleaseGeometry(g); }
};
using DevicePtr = std::unique_ptr<std::remove_pointer_t<RTCDevice>, DeviceDeleter>;
using ScenePtr = std::unique_ptr<std::remove_pointer_t<RTCScene>, SceneDeleter>;
using GeometryPtr = std::unique_ptr<std::remove_pointer_t<RTCGeometry>, GeometryDeleter>;

// The triangles' planes, for telling a ray's own surface from a real hit:
// float positions of a G-buffer lie on their triangle only to a few ulps, so
// a ray leaving a surface at a grazing angle can meet that surface again at
// a tiny t. A hit on a triangle whose plane passes (within rounding) through
// the ray's origin is that surface, whatever t it has.
struct Planes {
  std::vector<double> n;  // unit normal (3) and offset (1) per triangle; 0 for degenerate ones

  // Every plane, or where `moved` (a flag per vertex) is given, those of the
  // triangles with a moved corner: a refit of one object's frame leaves the
  // rest of a million planes as they were.
  void compute(const float* vertices, const unsigned* triangles, size_t count, int threads,
               const uint8_t* moved = nullptr) {
    if (!moved) n.assign(count * 4, 0.0);
    constexpr size_t kBlock = 1 << 15;
    const int blocks = static_cast<int>((count + kBlock - 1) / kBlock);
    parallel_rows(0, blocks, threads, [&](int b) {
      const size_t end = std::min(count, (static_cast<size_t>(b) + 1) * kBlock);
      for (size_t t = static_cast<size_t>(b) * kBlock; t < end; ++t) {
        const unsigned* corner = &triangles[3 * t];
        if (moved && !(moved[corner[0]] | moved[corner[1]] | moved[corner[2]])) continue;
        double* p = &n[4 * t];
        p[0] = p[1] = p[2] = p[3] = 0.0;
        const float* a = &vertices[3 * size_t(triangles[3 * t])];
        const float* bv = &vertices[3 * size_t(triangles[3 * t + 1])];
        const float* c = &vertices[3 * size_t(triangles[3 * t + 2])];
        const double e1[3] = {double(bv[0]) - a[0], double(bv[1]) - a[1], double(bv[2]) - a[2]};
        const double e2[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
        double nx = e1[1] * e2[2] - e1[2] * e2[1], ny = e1[2] * e2[0] - e1[0] * e2[2],
               nz = e1[0] * e2[1] - e1[1] * e2[0];
        const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
        if (!(len > 0.0)) continue;
        nx /= len, ny /= len, nz /= len;
        p[0] = nx, p[1] = ny, p[2] = nz, p[3] = -(nx * a[0] + ny * a[1] + nz * a[2]);
      }
    });
  }
  double distance(unsigned prim, D3 p) const {
    const double* q = &n[4 * prim];
    return std::fabs(q[0] * p.x + q[1] * p.y + q[2] * p.z + q[3]);
  }
};

// How far from a point its own surface may appear, relative to the point's
// magnitude: G-buffer positions are interpolated in float32 (ulp 6e-8), and
// a generous multiple keeps grazing rays off their own triangle. In a frame
// other than view space the vertices were rounded there, so the larger of
// the two magnitudes sets the scale.
constexpr double kSurfaceTolerance = 1e-5;

// View space -> the scene's frame. The identity is kept apart so that a mesh
// in view space is traced with the very floats it was before frames existed.
struct Frame {
  bool identity = true;
  double m[12] = {};

  explicit Frame(const Mat4& v) {
    static const Mat4 one{{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}};
    identity = v.m == one.m;
    for (int i = 0; i < 12; ++i) m[i] = v.m[i];
  }
  D3 point(D3 p) const {
    if (identity) return p;
    return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
            m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
  }
  // Not renormalised: an affine map keeps a ray's parameter, so t (and
  // max_distance, in view units) means the same point in both frames.
  D3 direction(D3 d) const {
    if (identity) return d;
    return {m[0] * d.x + m[1] * d.y + m[2] * d.z, m[4] * d.x + m[5] * d.y + m[6] * d.z,
            m[8] * d.x + m[9] * d.y + m[10] * d.z};
  }
};

// One ray of a batch, in view space, and what it met.
struct Query {
  D3 origin, dir;
  double tfar;
  bool found = false;  // it met a surface other than its own
  double t = 0.0;      // where, for Own::Skip
};

// A query on its way through Embree, in the scene's frame.
struct Live {
  D3 origin;
  float dir[3];
  double tolerance;  // kSurfaceTolerance x the origin's magnitude
  float own_t;       // a t at which the ray has gone at most half the tolerance
};

// What a ray does about hits on its own surface.
enum class Own {
  // The mirror rays, one per pixel: a filter drops such hits inside the one
  // traversal, which goes on to the next surface, and packets go through the
  // BVH as one frustum (Embree's coherent mode). Half of the floor's rays meet
  // their own triangle first, and asking again cost a second traversal each.
  Skip,
  // The rays back to the camera, one per hit on screen, ask only whether
  // any other surface lies on the way: Embree's occlusion query, which stops
  // at the first hit the same filter lets through. Each lane is traversed as
  // a ray of its own: the coherent traversal settles exact distance ties its
  // own way (27 pixels of the orthographic sample, whose camera rays run
  // exactly along an axis, came out otherwise).
  Block,
};

// A batch of mirror rays, each with where its report goes.
struct MirrorRays {
  std::vector<Query> rays;
  std::vector<float*> out;
  explicit MirrorRays(size_t n) { rays.reserve(n), out.reserve(n); }
  // The camera's ray `unit_from`, mirrored about `normal` at `from`, up to
  // max_distance; its report into `o`, zeroed here.
  void add(V3 from, V3 unit_from, V3 normal, float* o, double max_distance) {
    o[0] = o[1] = o[2] = o[3] = 0.0f;
    const V3 pivot = cpu::normalize(cpu::reflect(unit_from, normal));
    if (!cpu::finite(pivot)) return;
    rays.push_back(Query{d3(from), d3(pivot), max_distance});
    out.push_back(o);
  }
};

#if GLINT_EMBREE_MAJOR >= 4
using QueryContext = RTCRayQueryContext;
#else
using QueryContext = RTCIntersectContext;
#endif

// Embree hands the context pointer of a query to its filter: the lanes'
// origins ride behind it.
struct SkipContext {
  QueryContext base;
  const Planes* planes;
  const Live* lanes;  // indexed by the ray's id: its lane
};

// Embree calls this for every hit between tnear and the best so far. Is it
// the ray's own surface? The origin's distance from the plane through the hit
// along Embree's normal Ng is t |Ng.d| / |Ng|, no more than t |d|, and it
// agrees with the stored plane's (Planes::distance) to the hit's rounding, far
// below the tolerance. So the rays start at own_t, where they have gone half
// the tolerance: the hits before it, 70% of the bench floor's (its own
// neighbouring triangles at t ~ 0), are the ray's own surface and never reach
// this. A hit at more than twice the tolerance is another surface. Only those
// in between, 65 of 1.6 million on the bench floor, read the plane table,
// a cache miss each (32 MB at a million triangles), which decides as before.
void skip_own_surface(const RTCFilterFunctionNArguments* args) {
  const auto* c = reinterpret_cast<const SkipContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] == 0) continue;
    const Live& r = c->lanes[RTCRayN_id(args->ray, args->N, i)];
    const double t = RTCRayN_tfar(args->ray, args->N, i);
    if (t <= r.own_t) {  // t |d| <= tolerance / 2
      args->valid[i] = 0;
      continue;
    }
    const double nx = RTCHitN_Ng_x(args->hit, args->N, i), ny = RTCHitN_Ng_y(args->hit, args->N, i),
                 nz = RTCHitN_Ng_z(args->hit, args->N, i);
    const double along = t * (nx * r.dir[0] + ny * r.dir[1] + nz * r.dir[2]), n2 = nx * nx + ny * ny + nz * nz;
    if (along * along > 4.0 * r.tolerance * r.tolerance * n2) continue;  // more than twice the tolerance
    if (!(c->planes->distance(RTCHitN_primID(args->hit, args->N, i), r.origin) > r.tolerance))
      args->valid[i] = 0;
  }
}

// Embree's packets of 8 (AVX) and 16 (AVX-512): the scene takes the widest
// the processor runs natively.
template <int K>
struct Packet;
template <>
struct Packet<8> {
  using RayHit = RTCRayHit8;
#if GLINT_EMBREE_MAJOR >= 4
  static void intersect(const int* valid, RTCScene s, RayHit* rh, RTCIntersectArguments* a) {
    rtcIntersect8(valid, s, rh, a);
  }
  static void occluded(const int* valid, RTCScene s, RayHit* rh, RTCOccludedArguments* a) {
    rtcOccluded8(valid, s, &rh->ray, a);
  }
#else
  static void intersect(const int* valid, RTCScene s, RayHit* rh, RTCIntersectContext* c) {
    rtcIntersect8(valid, s, c, rh);
  }
  static void occluded(const int* valid, RTCScene s, RayHit* rh, RTCIntersectContext* c) {
    rtcOccluded8(valid, s, c, &rh->ray);
  }
#endif
};
template <>
struct Packet<16> {
  using RayHit = RTCRayHit16;
#if GLINT_EMBREE_MAJOR >= 4
  static void intersect(const int* valid, RTCScene s, RayHit* rh, RTCIntersectArguments* a) {
    rtcIntersect16(valid, s, rh, a);
  }
  static void occluded(const int* valid, RTCScene s, RayHit* rh, RTCOccludedArguments* a) {
    rtcOccluded16(valid, s, &rh->ray, a);
  }
#else
  static void intersect(const int* valid, RTCScene s, RayHit* rh, RTCIntersectContext* c) {
    rtcIntersect16(valid, s, c, rh);
  }
  static void occluded(const int* valid, RTCScene s, RayHit* rh, RTCIntersectContext* c) {
    rtcOccluded16(valid, s, c, &rh->ray);
  }
#endif
};

#if GLINT_EMBREE_MAJOR >= 4
// What both kinds of query take in Embree 4's argument structs.
template <class Args>
void filtered(Args& args, RTCRayQueryContext* context, RTCRayQueryFlags coherence) {
  args.context = context;
  args.flags = static_cast<RTCRayQueryFlags>(coherence | RTC_RAY_QUERY_FLAG_INVOKE_ARGUMENT_FILTER);
  args.filter = &skip_own_surface;
}
#endif

// Own::Skip: the nearest hit, coherent; Own::Block: any hit, ray by ray.
// Both through skip_own_surface. An occluded lane comes back with tfar -inf.
template <int K>
void query(const int* valid, RTCScene scene, typename Packet<K>::RayHit* rh, SkipContext* ctx, Own own) {
#if GLINT_EMBREE_MAJOR >= 4
  rtcInitRayQueryContext(&ctx->base);
  if (own == Own::Skip) {
    RTCIntersectArguments args;
    rtcInitIntersectArguments(&args);
    filtered(args, &ctx->base, RTC_RAY_QUERY_FLAG_COHERENT);
    Packet<K>::intersect(valid, scene, rh, &args);
  } else {
    RTCOccludedArguments args;
    rtcInitOccludedArguments(&args);
    filtered(args, &ctx->base, RTC_RAY_QUERY_FLAG_INCOHERENT);
    Packet<K>::occluded(valid, scene, rh, &args);
  }
#else
  rtcInitIntersectContext(&ctx->base);
  ctx->base.filter = &skip_own_surface;
  if (own == Own::Skip) {
    ctx->base.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    Packet<K>::intersect(valid, scene, rh, &ctx->base);
  } else {
    ctx->base.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    Packet<K>::occluded(valid, scene, rh, &ctx->base);
  }
#endif
}

double elapsed_ms(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since).count();
}

}  // namespace

const char* to_string(BvhWork work) {
  switch (work) {
    case BvhWork::Built:
      return "built";
    case BvhWork::Refit:
      return "refit";
    case BvhWork::Reused:
      return "reused";
  }
  return "?";
}

void validate_view_to_world(const Mat4& v) {
  for (double e : v.m)
    if (!std::isfinite(e)) throw InvalidArgument("view_to_world", "expected a finite 4x4 matrix");
  if (v(3, 0) != 0.0 || v(3, 1) != 0.0 || v(3, 2) != 0.0 || v(3, 3) != 1.0)
    throw InvalidArgument("view_to_world", "expected an affine matrix (last row 0, 0, 0, 1), got (" +
                                               std::to_string(v(3, 0)) + ", " + std::to_string(v(3, 1)) + ", " +
                                               std::to_string(v(3, 2)) + ", " + std::to_string(v(3, 3)) + ")");
  const double det = v(0, 0) * (v(1, 1) * v(2, 2) - v(1, 2) * v(2, 1)) -
                     v(0, 1) * (v(1, 0) * v(2, 2) - v(1, 2) * v(2, 0)) +
                     v(0, 2) * (v(1, 0) * v(2, 1) - v(1, 1) * v(2, 0));
  if (!(std::fabs(det) > 0.0) || !std::isfinite(det))
    throw InvalidArgument("view_to_world", "expected an invertible matrix, its 3x3 part is singular");
}

class ExactScene::Impl {
 public:
  explicit Impl(int threads) : threads_(threads) {
    // Embree's own worker threads build and refit the BVH; the rays run on ours.
    const std::string config = threads > 0 ? "threads=" + std::to_string(threads) : std::string();
    device_.reset(rtcNewDevice(config.empty() ? nullptr : config.c_str()));
    if (!device_)
      throw Error("glint: march \"exact\": Embree could not start (" + std::to_string(rtcGetDeviceError(nullptr)) +
                  ")");
    rtcSetDeviceErrorFunction(device_.get(), &on_device_error, &errors_);
    wide_ = rtcGetDeviceProperty(device_.get(), RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0;
  }

  // Callers hold `use` exclusively for these two. A build that fails leaves
  // the scene as it was; a refit that fails has already changed the vertices,
  // so the scene refuses to trace until a whole mesh rebuilds it.
  void build(const TriangleMesh& mesh) {
    ScenePtr scene(rtcNewScene(device_.get()));
    GeometryPtr geometry;
    // DYNAMIC: without it Embree 3 throws a committed BVH away and builds anew
    // even where every geometry asks for a refit. The filter flag lets the
    // mirror rays' queries bring their own (Own::Skip).
#if GLINT_EMBREE_MAJOR >= 4
    constexpr auto kFilter = RTC_SCENE_FLAG_FILTER_FUNCTION_IN_ARGUMENTS;
#else
    constexpr auto kFilter = RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION;
#endif
    rtcSetSceneFlags(scene.get(), static_cast<RTCSceneFlags>(RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_DYNAMIC | kFilter));
    // The two-level BVH: the only one whose geometries honour their own build
    // quality, REFIT among them. With one geometry its top level is the
    // geometry's BVH itself, so rays pay nothing for it.
    rtcSetSceneBuildQuality(scene.get(), RTC_BUILD_QUALITY_LOW);
    const size_t nv = mesh.vertices.size() / 3, nt = mesh.triangles.size() / 3;
    Planes planes;
    if (nt > 0) {
      geometry.reset(rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_TRIANGLE));
      // A SAH build the first time, a refit of it while the index buffer stays.
      rtcSetGeometryBuildQuality(geometry.get(), RTC_BUILD_QUALITY_REFIT);
      // Embree-owned buffers: it reads vertices 16 bytes at a time, which a
      // tightly packed caller array does not allow at its end.
      auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geometry.get(), RTC_BUFFER_TYPE_VERTEX, 0,
                                                            RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv));
      auto* f = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geometry.get(), RTC_BUFFER_TYPE_INDEX, 0,
                                                               RTC_FORMAT_UINT3, 3 * sizeof(unsigned), nt));
      if (v && f) {
        std::memcpy(v, mesh.vertices.data(), nv * 3 * sizeof(float));
        std::memcpy(f, mesh.triangles.data(), nt * 3 * sizeof(unsigned));
        rtcCommitGeometry(geometry.get());
        rtcAttachGeometry(scene.get(), geometry.get());
        planes.compute(v, f, nt, threads_);
      }
    }
    rtcCommitScene(scene.get());
    errors_.rethrow();
    geometry_ = std::move(geometry);
    scene_ = std::move(scene);
    planes_ = std::move(planes);
    vertices_ = nv, triangles_ = nt;
    broken_.clear();
  }

  // Where the vertices are the scene's already, there is nothing to do.
  BvhWork refit(const std::vector<float>& vertices) {
    if (!geometry_) return BvhWork::Reused;
    float* held = vertex_data();
    std::vector<uint8_t> moved(vertices_);
    bool any = false;
    for (size_t v = 0; v < vertices_; ++v) {
      moved[v] = std::memcmp(held + 3 * v, vertices.data() + 3 * v, 3 * sizeof(float)) != 0;
      any |= moved[v] != 0;
    }
    if (!any) return BvhWork::Reused;
    try {
      std::memcpy(held, vertices.data(), vertices.size() * sizeof(float));
      rtcUpdateGeometryBuffer(geometry_.get(), RTC_BUFFER_TYPE_VERTEX, 0);
      rtcCommitGeometry(geometry_.get());
      rtcCommitScene(scene_.get());
      errors_.rethrow();
      planes_.compute(held, index_data(), triangles_, threads_, moved.data());
    } catch (const std::exception& e) {
      broken_ = e.what();
      throw;
    }
    return BvhWork::Refit;
  }

  bool same_triangles(const std::vector<int32_t>& triangles) const {
    if (triangles.size() != triangles_ * 3) return false;
    return triangles_ == 0 || std::memcmp(index_data(), triangles.data(), triangles.size() * sizeof(int32_t)) == 0;
  }

  Image trace(const TraceInputs& in, const TraceOptions& opt, const Mat4& view_to_world, int threads) const;

  mutable std::shared_mutex use;  // traces share it; build and refit take it alone
  size_t vertices_ = 0, triangles_ = 0;

  // What the getters read, under a lock of its own: a caller asking what the
  // last update did (Blender's UI, say) must not wait out a rebuild in progress.
  struct Summary {
    BvhReport last;
    size_t vertices = 0, triangles = 0;
  };
  BvhReport report(BvhWork work, std::chrono::steady_clock::time_point start) {
    std::lock_guard<std::mutex> lock(summary_mu);
    summary = {{work, elapsed_ms(start)}, vertices_, triangles_};
    return summary.last;
  }
  Summary read_summary() const {
    std::lock_guard<std::mutex> lock(summary_mu);
    return summary;
  }
  std::string broken_;  // why the last refit failed; empty when the scene is whole

 private:
  float* vertex_data() const {
    return static_cast<float*>(rtcGetGeometryBufferData(geometry_.get(), RTC_BUFFER_TYPE_VERTEX, 0));
  }
  unsigned* index_data() const {
    return static_cast<unsigned*>(rtcGetGeometryBufferData(geometry_.get(), RTC_BUFFER_TYPE_INDEX, 0));
  }

  // Each query's ray, origin + t * dir (view space) for t in [0, tfar],
  // against the surfaces that do not pass through its origin: Own::Skip finds
  // the first hit, Own::Block whether there is any.
  void cast(const Frame& frame, std::vector<Query>& queries, Own own) const {
    if (wide_)
      cast_k<16>(frame, queries, own);
    else
      cast_k<8>(frame, queries, own);
  }
  template <int K>
  void cast_k(const Frame& frame, std::vector<Query>& queries, Own own) const;
  // The mirror rays of row y, then the rays back to the camera from their hits.
  // Each ray's report into its `out`, (0, 0, 0, 0) where it finds nothing
  // the camera sees.
  void trace_rays(const Frame& frame, const MarchSetup& s, MirrorRays& mirror) const;
  void trace_row(const Frame& frame, const MarchSetup& s, const Image* specular, int y, Image& out) const;
  // antialias > 0: the outline pixels of row y (cpu::outline_pixels()),
  // each with k more rays from inside it, resolved into `out`.
  void antialias_row(const Frame& frame, const MarchSetup& s, const Mat4& inverse_projection, int y,
                     const std::vector<int>& edges, int k, Image& out) const;

  mutable std::mutex summary_mu;
  Summary summary;
  int threads_;
  bool wide_ = false;         // packets of 16
  mutable ErrorSink errors_;  // before the device, which reports to it until released
  DevicePtr device_;
  ScenePtr scene_;
  GeometryPtr geometry_;
  Planes planes_;
};

template <int K>
void ExactScene::Impl::cast_k(const Frame& frame, std::vector<Query>& queries, Own own) const {
  // Neighbouring pixels' rays go to Embree K at a time and share the BVH's
  // upper levels.
  for (size_t first = 0; first < queries.size(); first += K) {
    const size_t n = std::min<size_t>(K, queries.size() - first);
    alignas(64) typename Packet<K>::RayHit rh;
    alignas(64) int valid[K];
    Live lanes[K];
    for (size_t k = 0; k < size_t(K); ++k) {
      valid[k] = k < n ? -1 : 0;
      if (k >= n) continue;
      const Query& q = queries[first + k];
      Live& r = lanes[k];
      r.origin = frame.point(q.origin);
      const D3 dir = frame.direction(q.dir);
      r.dir[0] = float(dir.x), r.dir[1] = float(dir.y), r.dir[2] = float(dir.z);
      const double scale = frame.identity ? norm(q.origin) : std::max(norm(q.origin), norm(r.origin));
      r.tolerance = kSurfaceTolerance * (scale + 1e-30);
      // Below half the tolerance over |d| by more than float rounding: the
      // filter's first test and tnear need only a bound, not the value.
      const float d2 = r.dir[0] * r.dir[0] + r.dir[1] * r.dir[1] + r.dir[2] * r.dir[2];
      r.own_t = float(0.5 * r.tolerance) / std::sqrt(d2) * 0.999f;
      if (!(r.own_t >= 0.0f)) r.own_t = 0.0f;  // a zero or non-finite direction
      rh.ray.org_x[k] = float(r.origin.x), rh.ray.org_y[k] = float(r.origin.y), rh.ray.org_z[k] = float(r.origin.z);
      rh.ray.dir_x[k] = r.dir[0], rh.ray.dir_y[k] = r.dir[1], rh.ray.dir_z[k] = r.dir[2];
      // The filter drops every hit before own_t: Embree need not report them.
      rh.ray.tnear[k] = r.own_t;
      rh.ray.tfar[k] = float(q.tfar);
      rh.ray.time[k] = 0.0f;
      rh.ray.mask[k] = 0xFFFFFFFFu;
      rh.ray.id[k] = static_cast<unsigned>(k);
      rh.ray.flags[k] = 0;
      rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      rh.hit.primID[k] = RTC_INVALID_GEOMETRY_ID;
    }
    SkipContext ctx;
    ctx.planes = &planes_;
    ctx.lanes = lanes;
    query<K>(valid, scene_.get(), &rh, &ctx, own);
    for (size_t k = 0; k < n; ++k) {
      Query& q = queries[first + k];
      if (own == Own::Block) {
        q.found = rh.ray.tfar[k] == -std::numeric_limits<float>::infinity();
      } else {
        q.found = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID;
        if (q.found) q.t = rh.ray.tfar[k];
      }
    }
  }
}

namespace {

// The plane clip z = -w, as an affine function of a view-space point.
double near_side(const double* P, D3 p) {
  return cpu::clip_row(P, 2, p.x, p.y, p.z) + cpu::clip_row(P, 3, p.x, p.y, p.z);
}

// Does the camera see `hit`? The segment from it towards the camera (the eye
// for perspective, the view axis for orthographic cameras), as far as the
// near plane, must be free of other surfaces: the answer where that needs no
// ray, else Ask and the ray in `back`.
enum class Sight { Seen, Unseen, Ask };
Sight camera_ray(const MarchSetup& s, D3 hit, Query& back) {
  D3 dir;
  if (s.eye_kind == EyeKind::Direction) {
    dir = {-double(s.eye[0]), -double(s.eye[1]), -double(s.eye[2])};
  } else {
    const D3 eye = s.eye_kind == EyeKind::Origin ? D3{0, 0, 0} : D3{s.eye[0], s.eye[1], s.eye[2]};
    dir = eye + hit * -1.0;
  }
  const double len = norm(dir);
  if (!(len > 0.0)) return Sight::Unseen;
  dir = dir * (1.0 / len);
  // near_side is affine along the segment: it reaches 0 at the near plane.
  const double n0 = near_side(s.projd, hit), n1 = near_side(s.projd, hit + dir);
  const double unbounded = s.eye_kind == EyeKind::Direction ? std::numeric_limits<float>::max() : len;
  double tfar = n0 > 0.0 && n0 - n1 > 0.0 ? n0 / (n0 - n1) : unbounded;
  if (s.eye_kind != EyeKind::Direction && tfar > len) tfar = len;
  if (!(tfar > 0.0)) return Sight::Seen;
  back = Query{hit, dir, tfar};
  return Sight::Ask;
}

}  // namespace

void ExactScene::Impl::trace_row(const Frame& frame, const MarchSetup& s, const Image* specular, int y,
                                 Image& out) const {
  MirrorRays rays(out.width);
  for (int x = 0; x < out.width; ++x) {
    float* o = out.px(x, y);
    V3 from, unit_from, normal;
    if ((specular && !is_reflective(specular->px(x, y))) || !cpu::read_origin(s, x, y, from, unit_from, normal)) {
      o[0] = o[1] = o[2] = o[3] = 0.0f;  // no ray: add() zeroes the others
      continue;
    }
    rays.add(from, unit_from, normal, o, s.opt.max_distance);
  }
  trace_rays(frame, s, rays);
}

namespace {

// Where the camera's ray through point (px, py) of the image (pixels) meets
// the plane through `p` with normal `n`, in view space: false where the plane
// is seen edge-on, or the point leaves the pixel's depth range as hiz's
// base_range() bounds it.
bool on_pixel_plane(const Mat4& inv, int w, int h, double px, double py, V3 p, V3 n, V3& at) {
  const double sx = px * (2.0 / w) - 1.0, sy = py * (2.0 / h) - 1.0;
  D3 e[2];
  for (int k = 0; k < 2; ++k) {  // NDC depths -1 (near) and 0: both finite for any camera
    const double sz = k == 0 ? -1.0 : 0.0;
    double v[4];
    for (int r = 0; r < 4; ++r)
      v[r] = inv.m[4 * r] * sx + inv.m[4 * r + 1] * sy + inv.m[4 * r + 2] * sz + inv.m[4 * r + 3];
    e[k] = {v[0] / v[3], v[1] / v[3], v[2] / v[3]};
  }
  const D3 d{e[1].x - e[0].x, e[1].y - e[0].y, e[1].z - e[0].z};
  const double nd = n.x * d.x + n.y * d.y + n.z * d.z;
  const double t = (n.x * (p.x - e[0].x) + n.y * (p.y - e[0].y) + n.z * (p.z - e[0].z)) / nd;
  const D3 q = e[0] + d * t;
  if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) return false;
  if (!(std::fabs(q.z - p.z) <= hiz::kFootprintSpread * std::fabs(p.z))) return false;
  at = {float(q.x), float(q.y), float(q.z)};
  return true;
}

}  // namespace

void ExactScene::Impl::antialias_row(const Frame& frame, const MarchSetup& s, const Mat4& inverse_projection,
                                     int y, const std::vector<int>& edges, int k, Image& out) const {
  if (edges.empty()) return;
  const int w = out.width, h = out.height;
  std::vector<float> samples(edges.size() * static_cast<size_t>(k) * 4);
  MirrorRays rays(edges.size() * static_cast<size_t>(k));
  for (size_t e = 0; e < edges.size(); ++e) {
    const int x = edges[e];
    const float* c = out.px(x, y);
    V3 from, unit_from, normal;
    const bool origin = cpu::read_origin(s, x, y, from, unit_from, normal);
    for (int j = 0; j < k; ++j) {
      float* o = samples.data() + (e * k + j) * 4;
      o[0] = c[0], o[1] = c[1], o[2] = c[2], o[3] = c[3];  // a sample without a ray of its own
      V3 at, incident;
      if (!origin ||
          !on_pixel_plane(inverse_projection, w, h, x + 0.5 + cpu::kAaOffset[j][0], y + 0.5 + cpu::kAaOffset[j][1],
                          from, normal, at) ||
          !cpu::incident_direction(s, at, incident))
        continue;
      rays.add(at, incident, normal, o, s.opt.max_distance);
    }
  }
  trace_rays(frame, s, rays);
  for (size_t e = 0; e < edges.size(); ++e) {
    float* o = out.px(edges[e], y);
    cpu::resolve_outline(o, samples.data() + e * k * 4, k, static_cast<float>(w), static_cast<float>(h), o);
  }
}

void ExactScene::Impl::trace_rays(const Frame& frame, const MarchSetup& s, MirrorRays& rays) const {
  using cpu::clip_row;
  std::vector<Query>& mirror = rays.rays;
  const std::vector<float*>& mirror_x = rays.out;
  std::vector<Query> back;
  std::vector<float*> back_x;
  cast(frame, mirror, Own::Skip);
  for (size_t i = 0; i < mirror.size(); ++i) {
    const Query& q = mirror[i];
    if (!q.found) continue;
    const D3 hit = q.origin + q.dir * q.t;
    const double* P = s.projd;
    const double w = clip_row(P, 3, hit.x, hit.y, hit.z);
    if (!(w > 0.0)) continue;
    const double z = clip_row(P, 2, hit.x, hit.y, hit.z) / w;
    const double u = clip_row(P, 0, hit.x, hit.y, hit.z) / w * 0.5 + 0.5;
    const double v = clip_row(P, 1, hit.x, hit.y, hit.z) / w * 0.5 + 0.5;
    if (!(z >= -1.0 && z <= 1.0 && u >= 0.0 && u < 1.0 && v >= 0.0 && v < 1.0)) continue;
    Query ray{};
    const Sight sight = camera_ray(s, hit, ray);
    if (sight == Sight::Unseen) continue;
    if (sight == Sight::Ask) {
      back.push_back(ray);
      back_x.push_back(mirror_x[i]);
    }
    // Written now, taken back below where a surface hides the hit.
    float* o = mirror_x[i];
    o[0] = float(u), o[1] = float(v), o[2] = o[3] = 1.0f;
  }
  cast(frame, back, Own::Block);
  for (size_t i = 0; i < back.size(); ++i) {
    if (!back[i].found) continue;
    float* o = back_x[i];
    o[0] = o[1] = o[2] = o[3] = 0.0f;
  }
}

Image ExactScene::Impl::trace(const TraceInputs& in, const TraceOptions& opt, const Mat4& view_to_world,
                              int threads) const {
  std::shared_lock<std::shared_mutex> lock(use);
  if (!broken_.empty())
    throw Error("glint: march \"exact\": the scene's last update failed (" + broken_ +
                "); update it with its vertices and triangles to rebuild it");
  const Frame frame(view_to_world);
  const MarchSetup setup = cpu::make_setup(in.position, in.normal, in.projection, opt, nullptr);
  // Every texel is written by its row.
  Image out = Image::uninitialized(in.position.width, in.position.height);
  parallel_rows(0, out.height, threads, [&](int y) { trace_row(frame, setup, in.specular, y, out); });
  errors_.rethrow();
  if (opt.antialias > 0) {
    // A row writes only its own outline pixels, which no other row reads by then.
    const std::vector<std::vector<int>> edges = cpu::outline_pixels(in, out, threads);
    const Mat4 inv = inverse(in.projection);
    const int k = std::min(opt.antialias, 4);
    parallel_rows(0, out.height, threads, [&](int y) { antialias_row(frame, setup, inv, y, edges[y], k, out); });
    errors_.rethrow();
  }
  return out;
}

namespace {
void require_arrays(const TriangleMesh& mesh) {
  if (mesh.scene) throw InvalidArgument("mesh", "expected vertices and triangles, got an ExactScene");
  validate(mesh);
}
}  // namespace

ExactScene::ExactScene(const TriangleMesh& mesh, int threads) {
  const auto start = std::chrono::steady_clock::now();
  require_arrays(mesh);
  impl_ = std::make_unique<Impl>(threads);
  impl_->build(mesh);
  impl_->report(BvhWork::Built, start);
}

ExactScene::~ExactScene() = default;

BvhReport ExactScene::update_vertices(const std::vector<float>& vertices) {
  std::unique_lock<std::shared_mutex> lock(impl_->use);
  const auto start = std::chrono::steady_clock::now();
  if (vertices.size() != impl_->vertices_ * 3)
    throw InvalidArgument("vertices", "expected " + std::to_string(impl_->vertices_) +
                                          " vertices (the scene's; pass triangles too to change the mesh), got " +
                                          std::to_string(vertices.size()) + " floats");
  for (size_t k = 0; k < vertices.size(); ++k)
    if (!std::isfinite(vertices[k]))
      throw InvalidArgument("vertices", "vertex " + std::to_string(k / 3) + " is not finite");
  if (!impl_->broken_.empty())
    throw Error("glint: march \"exact\": the scene's last update failed (" + impl_->broken_ +
                "); update it with its vertices and triangles to rebuild it");
  return impl_->report(impl_->refit(vertices), start);
}

BvhReport ExactScene::update(const TriangleMesh& mesh) {
  std::unique_lock<std::shared_mutex> lock(impl_->use);
  const auto start = std::chrono::steady_clock::now();
  require_arrays(mesh);
  BvhWork work = BvhWork::Built;
  if (impl_->broken_.empty() && mesh.vertices.size() == impl_->vertices_ * 3 &&
      impl_->same_triangles(mesh.triangles))
    work = impl_->refit(mesh.vertices);
  else
    impl_->build(mesh);
  return impl_->report(work, start);
}

BvhReport ExactScene::last_update() const { return impl_->read_summary().last; }

size_t ExactScene::vertex_count() const { return impl_->read_summary().vertices; }

size_t ExactScene::triangle_count() const { return impl_->read_summary().triangles; }

namespace cpu {

Image trace_exact(const TraceInputs& in, const TraceOptions& opt, int threads) {
  const TriangleMesh& mesh = *in.mesh;
  validate_view_to_world(mesh.view_to_world);
  if (mesh.scene) {
    if (!mesh.vertices.empty() || !mesh.triangles.empty())
      throw InvalidArgument("mesh", "expected either (vertices, triangles) or an ExactScene, got both");
    return mesh.scene->impl().trace(in, opt, mesh.view_to_world, threads);
  }
  const ExactScene once(mesh, threads);
  return once.impl().trace(in, opt, mesh.view_to_world, threads);
}

}  // namespace cpu
}  // namespace glint
