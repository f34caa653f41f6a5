// glint_core's memory: the per-call limit and the buffer pool kept between calls.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <optional>

#include "glint/buffer_pool.h"
#include "glint/errors.h"
#include "glint/memory.h"

namespace pyb = pybind11;
using namespace pybind11::literals;

namespace glint::py {
namespace {

constexpr double kMiB = 1024.0 * 1024.0;

pyb::dict pool_dict(const BufferPoolStats& s) {
  return pyb::dict("held_mb"_a = static_cast<double>(s.held_bytes) / kMiB,
                   "limit_mb"_a = static_cast<double>(s.limit_bytes) / kMiB,
                   "max_idle_s"_a = s.max_idle_seconds, "reused"_a = s.reused, "allocated"_a = s.allocated);
}

}  // namespace

void bind_memory(pyb::module_& m) {
  m.attr("MEMORY_LIMIT_ENV") = kMemoryLimitEnv;
  m.def(
      "memory_limit",
      [](double limit_mb) {
        const MemoryLimit l = memory_limit(limit_mb);
        return pyb::make_tuple(l.bytes, l.source);
      },
      "memory_limit_mb"_a = 0.0,
      "(bytes, source): the memory one call may allocate with this memory_limit_mb (0: the\n"
      "default, GLINT_MEMORY_LIMIT_MB or half of physical memory) and where it came from.");
  m.def(
      "buffer_pool",
      [](std::optional<double> limit_mb, std::optional<double> max_idle_s) {
        BufferPoolStats s = buffer_pool_stats();
        if (limit_mb) {
          if (!std::isfinite(*limit_mb) || *limit_mb < 0 || *limit_mb > 1e12)
            throw InvalidArgument("limit_mb", "expected a finite number of MiB >= 0");
          s.limit_bytes = static_cast<uint64_t>(*limit_mb * kMiB);
        }
        if (max_idle_s) {
          if (!std::isfinite(*max_idle_s) || *max_idle_s < 0)
            throw InvalidArgument("max_idle_s", "expected a finite number of seconds >= 0");
          s.max_idle_seconds = *max_idle_s;
        }
        if (limit_mb || max_idle_s) configure_buffer_pool(s.limit_bytes, s.max_idle_seconds);
        return pool_dict(buffer_pool_stats());
      },
      pyb::kw_only(), "limit_mb"_a = pyb::none(), "max_idle_s"_a = pyb::none(),
      "The pool of large buffers (images, pyramids) kept between calls so that the next\n"
      "frame does not fault its memory in again: dict(held_mb, limit_mb, max_idle_s, reused,\n"
      "allocated). limit_mb (0 turns it off) and max_idle_s (a held buffer unused this long\n"
      "is freed) change it when given. The memory held is outside every call's memory limit.");
  m.def(
      "release_buffers",
      [](bool idle_only) {
        return static_cast<double>(idle_only ? trim_buffer_pool() : release_buffer_pool()) / kMiB;
      },
      pyb::kw_only(), "idle_only"_a = false,
      "Frees the buffer pool's held buffers (with idle_only, only those unused for max_idle_s);\n"
      "returns the MiB freed.");
}

}  // namespace glint::py
