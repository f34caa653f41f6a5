// The memory budget (glint/memory.h): the limit, and what each request costs.
//
// Costs are counted in bytes per pixel (P = width * height) and per triangle,
// from the buffers each stage allocates. They are upper bounds of the large
// buffers on purpose: refusing a request that would just have fitted costs a
// retry at a lower size, letting through one that does not fit costs the process.
#include "glint/memory.h"

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "glint/marches.h"
#include "glint/mesh.h"
#include "glint/raster.h"
#include "glint/stages.h"

namespace glint {
namespace {

constexpr uint64_t kMiB = uint64_t{1} << 20;
constexpr uint64_t kImage = 16;  // bytes per pixel of an RGBA float32 Image

uint64_t mib_to_bytes(double mb) {
  const double b = mb * static_cast<double>(kMiB);
  return b >= 1.8e19 ? UINT64_MAX : static_cast<uint64_t>(b);
}

// Per-pixel bytes a march allocates beside its output on the CPU (its row
// of the table of marches says).
uint64_t march_scratch(March march) { return march_info(march).scratch_per_pixel; }

}  // namespace

uint64_t physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return 0;
  return static_cast<uint64_t>(pages) * static_cast<uint64_t>(page);
}

MemoryLimit memory_limit(double limit_mb) {
  if (!std::isfinite(limit_mb) || limit_mb < 0.0)
    throw InvalidArgument("memory_limit_mb",
                          "expected a size in MiB > 0 (or 0 for the default), got " +
                              std::to_string(limit_mb));
  if (limit_mb > 0.0) return {mib_to_bytes(limit_mb), "memory_limit_mb"};
  if (const char* env = std::getenv(kMemoryLimitEnv); env && *env) {
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(env, &end);
    if (errno != 0 || end == env || *end != '\0' || !std::isfinite(v) || v < 0.0)
      throw InvalidArgument(kMemoryLimitEnv, std::string("expected a size in MiB > 0 (or 0 for the "
                                                         "default), got \"") + env + "\"");
    if (v > 0.0) return {mib_to_bytes(v), kMemoryLimitEnv};
  }
  const uint64_t phys = physical_memory_bytes();
  // Unknown physical memory: no default limit rather than a guessed one.
  if (phys == 0) return {UINT64_MAX, "default (physical memory unknown: no limit)"};
  const uint64_t share = static_cast<uint64_t>(static_cast<double>(phys) * kDefaultMemoryShare);
  return {share, "default: " + std::to_string(static_cast<int>(kDefaultMemoryShare * 100)) +
                     "% of this machine's " + format_bytes(phys)};
}

std::string format_bytes(uint64_t bytes) {
  char buf[64];
  const double b = static_cast<double>(bytes);
  if (bytes >= (uint64_t{1} << 30))
    std::snprintf(buf, sizeof buf, "%.2f GiB", b / double(uint64_t{1} << 30));
  else
    std::snprintf(buf, sizeof buf, "%.1f MiB", b / double(kMiB));
  return buf;
}

void require_memory(uint64_t bytes, const std::string& request, double limit_mb) {
  const MemoryLimit limit = memory_limit(limit_mb);
  if (bytes <= limit.bytes) return;
  throw MemoryLimitExceeded(
      request + " needs about " + format_bytes(bytes) + ", over the memory limit of " +
          format_bytes(limit.bytes) + " (" + limit.source +
          "); ask for a smaller size, or raise the limit with memory_limit_mb= (MiB) or the " +
          kMemoryLimitEnv + " environment variable",
      bytes, limit.bytes);
}

uint64_t trace_bytes(int width, int height, March march, bool gl, uint64_t triangles) {
  const uint64_t p = static_cast<uint64_t>(width) * static_cast<uint64_t>(height);
  const uint64_t mesh = triangles * march_info(march).scratch_per_triangle;
  // A march with no GL form runs its CPU code whatever the backend.
  if (!gl || !march_info(march).gl_program) return p * (kImage + march_scratch(march)) + mesh;
  // Up to four input textures (position, normal, specular, back_position), the
  // render target, the read-back image, and the pyramid where a march has one.
  return p * (4 * kImage + kImage + kImage + march_scratch(march));
}

uint64_t pipeline_bytes(int width, int height, const PipelineOptions& opt, bool gl) {
  const uint64_t p = static_cast<uint64_t>(width) * static_cast<uint64_t>(height);
  // reflection_color, blur scratch and result, reflection, combined; the GL
  // backend also holds each stage's input textures and render target.
  const uint64_t stages = 5 * kImage + (gl ? 3 * kImage : 0);
  return trace_bytes(width, height, opt.trace.march, gl) + p * stages;
}

uint64_t raster_bytes(int width, int height, uint64_t triangles, bool back_layer, bool back_albedo,
                      bool gl) {
  const uint64_t p = static_cast<uint64_t>(width) * static_cast<uint64_t>(height);
  // CPU: a double depth and an int32 winner per pixel, then three RGBA images;
  // the back layer repeats depth and winner and adds one image, its albedo
  // one more. Per triangle: its screen set-up and band bins (clipping can
  // split one into several).
  // GL: three RGBA32F targets and a depth buffer, their read-back, and the
  // vertex buffers; the back layer's albedo is a target and a read-back.
  const uint64_t front = gl ? 3 * kImage + 4 + 3 * kImage : 8 + 4 + 3 * kImage;
  const uint64_t back = back_layer ? (gl ? kImage + 4 + kImage : 8 + 4 + kImage) : 0;
  const uint64_t albedo = back_albedo ? (gl ? 2 * kImage : kImage) : 0;
  return p * (front + back + albedo) + triangles * 256;
}

uint64_t exr_read_bytes(int64_t width, int64_t height, uint64_t layers) {
  const uint64_t p = static_cast<uint64_t>(width) * static_cast<uint64_t>(height);
  // One RGBA image per layer, plus the reader's strip scratch (16 MiB at most).
  return layers * p * kImage + 16 * kMiB;
}

namespace {
std::string size_of(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }
}  // namespace

void require_trace_memory(const TraceInputs& in, const TraceOptions& opt, bool gl) {
  const int w = in.position.width, h = in.position.height;
  const uint64_t triangles = in.mesh ? in.mesh->triangles.size() / 3 : 0;
  require_memory(trace_bytes(w, h, opt.march, gl, triangles), "trace at " + size_of(w, h), opt.memory_limit_mb);
}

void require_raster_memory(const RasterInputs& in, bool gl) {
  require_memory(raster_bytes(in.width, in.height, in.mesh.triangle_count(), in.back_layer,
                              in.back_albedo, gl),
                 "rasterize at " + size_of(in.width, in.height), in.memory_limit_mb);
}

}  // namespace glint
