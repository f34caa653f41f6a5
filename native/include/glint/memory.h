// Memory known before it is taken: every entry point (trace, run_pipeline,
// rasterize, read_exr, and the bindings around them) works out from its sizes
// the bytes a request will allocate and refuses one over the limit before
// allocating anything, instead of growing until the allocator or the kernel's
// OOM killer ends the process (inside Blender: the whole render lost).
//
// The limit, per call: the caller's `memory_limit_mb` when positive, else the
// GLINT_MEMORY_LIMIT_MB environment variable when set, else
// kDefaultMemoryShare of the machine's physical memory. The estimates are
// upper bounds of the large buffers (images, depth buffers, pyramids, copies
// made at the boundary); small bookkeeping is left out. docs/hardening.md.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

#include "glint/errors.h"
#include "glint/options.h"

namespace glint {

// Share of physical memory one call may take when nothing else says.
constexpr double kDefaultMemoryShare = 0.5;
// The environment variable, in MiB (a positive number; 0 or unset: the default).
constexpr const char* kMemoryLimitEnv = "GLINT_MEMORY_LIMIT_MB";

// A request whose estimated allocation is over the limit. The bindings map it
// to glint_core.MemoryLimitExceeded, a MemoryError.
class MemoryLimitExceeded : public Error {
 public:
  MemoryLimitExceeded(const std::string& message, uint64_t needed, uint64_t limit)
      : Error(message), needed_(needed), limit_(limit) {}
  uint64_t needed_bytes() const { return needed_; }
  uint64_t limit_bytes() const { return limit_; }

 private:
  uint64_t needed_, limit_;
};

// The machine's physical memory in bytes (sysconf), 0 when unknown.
uint64_t physical_memory_bytes();

// The limit a call with option `limit_mb` gets, in bytes, and where it came from
// ("memory_limit_mb", "GLINT_MEMORY_LIMIT_MB" or "default"). Throws
// InvalidArgument for a negative or non-finite option or a malformed variable.
struct MemoryLimit {
  uint64_t bytes = 0;
  std::string source;
};
MemoryLimit memory_limit(double limit_mb = 0.0);

// Throws MemoryLimitExceeded when `bytes` is over the limit; `request` says
// what was asked for ("rasterize at 32768x32768"), for the message.
void require_memory(uint64_t bytes, const std::string& request, double limit_mb = 0.0);

// Estimates, in bytes. `gl`: the OpenGL backend (textures live in driver
// memory, on llvmpipe the same RAM, plus a read-back copy).
// triangles: of the mesh a march that traces triangles reads (0 for the others).
uint64_t trace_bytes(int width, int height, March march, bool gl, uint64_t triangles = 0);
uint64_t pipeline_bytes(int width, int height, const PipelineOptions& opt, bool gl);
uint64_t raster_bytes(int width, int height, uint64_t triangles, bool back_layer, bool back_albedo,
                      bool gl);
uint64_t exr_read_bytes(int64_t width, int64_t height, uint64_t layers);

// The checks the backends make on entry, before allocating anything.
struct TraceInputs;
struct RasterInputs;
void require_trace_memory(const TraceInputs& in, const TraceOptions& opt, bool gl);
void require_raster_memory(const RasterInputs& in, bool gl);

// "1.50 GiB", "12.0 MiB": sizes as messages print them.
std::string format_bytes(uint64_t bytes);

}  // namespace glint
