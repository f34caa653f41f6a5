// march="exact": every pixel's mirror ray traced against the scene's own
// triangles with Embree (3 or 4, whichever the distribution has), the answer
// every screen-space march approximates.
// The rules are SPEC's: the first hit within max_distance, reported as
// (u, v, 1, 1) only where the camera sees that point; no fades.
#if GLINT_EMBREE_MAJOR >= 4
#include <embree4/rtcore.h>
#else
#include <embree3/rtcore.h>
#endif

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>

#include "glint/errors.h"
#include "glint/mesh.h"
#include "parallel.h"
#include "ray.h"
#include "trace.h"

namespace glint::cpu {
namespace {

struct D3 {
  double x, y, z;
};
D3 d3(V3 v) { return {v.x, v.y, v.z}; }
D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 operator*(D3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double norm(D3 a) { return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z); }

// Embree reports errors through a callback; the first one of a call becomes
// the exception the caller sees.
void on_device_error(void* user, RTCError code, const char* what) {
  auto* first = static_cast<std::string*>(user);
  if (first->empty()) first->assign("Embree error " + std::to_string(code) + ": " + (what ? what : ""));
}

struct DeviceDeleter {
  void operator()(RTCDevice d) const { rtcReleaseDevice(d); }
};
struct SceneDeleter {
  void operator()(RTCScene s) const { rtcReleaseScene(s); }
};
using DevicePtr = std::unique_ptr<std::remove_pointer_t<RTCDevice>, DeviceDeleter>;
using ScenePtr = std::unique_ptr<std::remove_pointer_t<RTCScene>, SceneDeleter>;

// The triangles' planes, for telling a ray's own surface from a real hit:
// float positions of a G-buffer lie on their triangle only to a few ulps, so
// a ray leaving a surface at a grazing angle can meet that surface again at
// a tiny t. A hit on a triangle whose plane passes (within rounding) through
// the ray's origin is that surface, whatever t it has.
struct Planes {
  std::vector<double> n;  // unit normal (3) and offset (1) per triangle; 0 for degenerate ones
  explicit Planes(const TriangleMesh& m) : n(m.triangles.size() / 3 * 4, 0.0) {
    for (size_t t = 0; t < m.triangles.size() / 3; ++t) {
      const float* a = &m.vertices[3 * m.triangles[3 * t]];
      const float* b = &m.vertices[3 * m.triangles[3 * t + 1]];
      const float* c = &m.vertices[3 * m.triangles[3 * t + 2]];
      const double e1[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
      const double e2[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
      double nx = e1[1] * e2[2] - e1[2] * e2[1], ny = e1[2] * e2[0] - e1[0] * e2[2],
             nz = e1[0] * e2[1] - e1[1] * e2[0];
      const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
      if (!(len > 0.0)) continue;
      nx /= len, ny /= len, nz /= len;
      double* p = &n[4 * t];
      p[0] = nx, p[1] = ny, p[2] = nz, p[3] = -(nx * a[0] + ny * a[1] + nz * a[2]);
    }
  }
  double distance(unsigned prim, D3 p) const {
    const double* q = &n[4 * prim];
    return std::fabs(q[0] * p.x + q[1] * p.y + q[2] * p.z + q[3]);
  }
};

// How far from a point its own surface may appear, relative to the point's
// magnitude: G-buffer positions are interpolated in float32 (ulp 6e-8), and
// a generous multiple keeps grazing rays off their own triangle.
constexpr double kSurfaceTolerance = 1e-5;

// The first hit along origin + t * dir for t in (0, tfar] that is not on a
// surface through `origin` itself; false where there is none.
bool first_hit(RTCScene scene, const Planes& planes, D3 origin, D3 dir, double tfar, double& t_hit,
               unsigned& prim) {
  const double scale = norm(origin) + 1e-30;
  double tnear = 0.0;
  // A handful of coplanar neighbours at most; past that the ray is skimming
  // its own surface and reflects nothing.
  for (int attempt = 0; attempt < 8; ++attempt) {
    RTCRayHit rh;
    rh.ray.org_x = float(origin.x), rh.ray.org_y = float(origin.y), rh.ray.org_z = float(origin.z);
    rh.ray.dir_x = float(dir.x), rh.ray.dir_y = float(dir.y), rh.ray.dir_z = float(dir.z);
    rh.ray.tnear = float(tnear);
    rh.ray.tfar = float(tfar);
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
#if GLINT_EMBREE_MAJOR >= 4
    rtcIntersect1(scene, &rh);  // Embree 4 folded the context into optional arguments
#else
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcIntersect1(scene, &ctx, &rh);
#endif
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    if (planes.distance(rh.hit.primID, origin) > kSurfaceTolerance * scale) {
      t_hit = rh.ray.tfar;
      prim = rh.hit.primID;
      return true;
    }
    // Step just past this hit: the next float of t, scaled so that it moves.
    tnear = std::nextafter(float(rh.ray.tfar), std::numeric_limits<float>::infinity());
    if (!(tnear < tfar)) return false;
  }
  return false;
}

// The plane clip z = -w, as an affine function of a view-space point.
double near_side(const double* P, D3 p) {
  return clip_row(P, 2, p.x, p.y, p.z) + clip_row(P, 3, p.x, p.y, p.z);
}

// Does the camera see `hit`? The segment from it towards the camera, as far
// as the near plane, must be free of other surfaces.
bool camera_sees(RTCScene scene, const Planes& planes, const MarchSetup& s, D3 hit) {
  D3 back;
  if (s.eye_kind == EyeKind::Direction) {
    back = {-double(s.eye[0]), -double(s.eye[1]), -double(s.eye[2])};
  } else {
    const D3 eye = s.eye_kind == EyeKind::Origin ? D3{0, 0, 0} : D3{s.eye[0], s.eye[1], s.eye[2]};
    back = eye + hit * -1.0;
  }
  const double len = norm(back);
  if (!(len > 0.0)) return false;
  back = back * (1.0 / len);
  // near_side is affine along the segment: it reaches 0 at the near plane.
  const double n0 = near_side(s.projd, hit), n1 = near_side(s.projd, hit + back);
  const double unbounded = s.eye_kind == EyeKind::Direction ? std::numeric_limits<float>::max() : len;
  double tfar = n0 > 0.0 && n0 - n1 > 0.0 ? n0 / (n0 - n1) : unbounded;
  if (s.eye_kind != EyeKind::Direction && tfar > len) tfar = len;
  if (!(tfar > 0.0)) return true;
  double t;
  unsigned prim;
  return !first_hit(scene, planes, hit, back, tfar, t, prim);
}

ScenePtr build_scene(RTCDevice device, const TriangleMesh& mesh) {
  ScenePtr scene(rtcNewScene(device));
  rtcSetSceneFlags(scene.get(), RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene.get(), RTC_BUILD_QUALITY_MEDIUM);
  const size_t nv = mesh.vertices.size() / 3, nt = mesh.triangles.size() / 3;
  if (nt > 0) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    // Embree-owned buffers: it reads vertices 16 bytes at a time, which a
    // tightly packed caller array does not allow at its end.
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), nv));
    auto* f = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                             3 * sizeof(unsigned), nt));
    if (v && f) {
      std::memcpy(v, mesh.vertices.data(), nv * 3 * sizeof(float));
      std::memcpy(f, mesh.triangles.data(), nt * 3 * sizeof(unsigned));
      rtcCommitGeometry(g);
      rtcAttachGeometry(scene.get(), g);
    }
    rtcReleaseGeometry(g);
  }
  rtcCommitScene(scene.get());
  return scene;
}

void march_exact(RTCScene scene, const Planes& planes, const MarchSetup& s, int x, int y, float out[4]) {
  out[0] = out[1] = out[2] = out[3] = 0.0f;
  V3 from, unit_from, normal;
  if (!read_origin(s, x, y, from, unit_from, normal)) return;
  const V3 pivot = normalize(reflect(unit_from, normal));
  if (!finite(pivot)) return;
  double t;
  unsigned prim;
  if (!first_hit(scene, planes, d3(from), d3(pivot), s.opt.max_distance, t, prim)) return;
  const D3 hit = d3(from) + d3(pivot) * t;
  const double* P = s.projd;
  const double w = clip_row(P, 3, hit.x, hit.y, hit.z);
  if (!(w > 0.0)) return;
  const double z = clip_row(P, 2, hit.x, hit.y, hit.z) / w;
  const double u = clip_row(P, 0, hit.x, hit.y, hit.z) / w * 0.5 + 0.5;
  const double v = clip_row(P, 1, hit.x, hit.y, hit.z) / w * 0.5 + 0.5;
  if (!(z >= -1.0 && z <= 1.0 && u >= 0.0 && u < 1.0 && v >= 0.0 && v < 1.0)) return;
  if (!camera_sees(scene, planes, s, hit)) return;
  out[0] = float(u), out[1] = float(v), out[2] = out[3] = 1.0f;
}

}  // namespace

Image trace_exact(const TraceInputs& in, const TraceOptions& opt, int threads) {
  validate(*in.mesh);
  std::string error;
  // Embree's own worker threads build the BVH; the rays run on ours.
  const std::string config = threads > 0 ? "threads=" + std::to_string(threads) : std::string();
  DevicePtr device(rtcNewDevice(config.empty() ? nullptr : config.c_str()));
  if (!device) throw Error("glint: march \"exact\": Embree could not start (" + std::to_string(rtcGetDeviceError(nullptr)) + ")");
  rtcSetDeviceErrorFunction(device.get(), &on_device_error, &error);
  const ScenePtr scene = build_scene(device.get(), *in.mesh);
  if (!error.empty()) throw Error("glint: march \"exact\": " + error);
  const Planes planes(*in.mesh);
  const MarchSetup setup = make_setup(in.position, in.normal, in.projection, opt, nullptr);
  Image out(in.position.width, in.position.height);
  const Image* spec = in.specular;
  parallel_rows(0, out.height, threads, [&](int y) {
    for (int x = 0; x < out.width; ++x) {
      if (spec && !is_reflective(spec->px(x, y))) continue;
      march_exact(scene.get(), planes, setup, x, y, out.px(x, y));
    }
  });
  if (!error.empty()) throw Error("glint: march \"exact\": " + error);
  return out;
}

}  // namespace glint::cpu
