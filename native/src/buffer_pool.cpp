// The buffer pool (glint/buffer_pool.h).
//
// Sizes are rounded up to 2 MiB: buffers then start on a huge-page boundary
// (asked for with MADV_HUGEPAGE, a hint the kernel may refuse), and images of
// nearly the same size share blocks. A request takes the most recently freed
// block of its rounded size, whose pages are the likeliest still in cache.
// The bookkeeping is a short list under one mutex: a frame makes a few dozen
// large requests, each worth milliseconds of page faults.
#include "glint/buffer_pool.h"

#include <sys/mman.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <new>
#include <vector>

#include "glint/errors.h"
#include "glint/memory.h"

namespace glint {
namespace {

using Clock = std::chrono::steady_clock;
constexpr size_t kHuge = size_t{2} << 20;

struct Block {
  void* p;
  size_t bytes;
  Clock::time_point freed;
};

uint64_t default_limit() {
#if defined(__SANITIZE_ADDRESS__)
  return 0;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
  return 0;
#endif
#endif
  const uint64_t gib = uint64_t{1} << 30;
  const uint64_t share = physical_memory_bytes() / 16;
  return share == 0 ? gib : std::min(gib, share);
}

size_t rounded(size_t bytes) { return bytes > SIZE_MAX - kHuge ? 0 : (bytes + kHuge - 1) & ~(kHuge - 1); }

void* fresh(size_t size) {
  void* p = std::aligned_alloc(kHuge, size);
  if (!p) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
  madvise(p, size, MADV_HUGEPAGE);
#endif
  return p;
}

struct Pool {
  std::mutex mutex;
  std::vector<Block> held;  // oldest first
  BufferPoolStats stats{0, default_limit(), 120.0, 0, 0};

  // Frees blocks (oldest first) while `over` says so; under the mutex.
  template <class Pred>
  uint64_t drop_while(Pred over) {
    uint64_t freed = 0;
    size_t k = 0;
    while (k < held.size() && over(held[k])) {
      std::free(held[k].p);
      freed += held[k].bytes;
      stats.held_bytes -= held[k].bytes;
      ++k;
    }
    held.erase(held.begin(), held.begin() + static_cast<long>(k));
    return freed;
  }
  uint64_t drop_idle(Clock::time_point now) {
    const auto idle = std::chrono::duration<double>(stats.max_idle_seconds);
    return drop_while([&](const Block& b) { return now - b.freed > idle; });
  }
  void fit_limit() {
    drop_while([&](const Block&) { return stats.held_bytes > stats.limit_bytes; });
  }
};

// Never destroyed: numpy arrays owning pool buffers may be freed while the
// interpreter shuts down, after static destructors would have run.
Pool& pool() {
  static Pool* p = new Pool;
  return *p;
}

}  // namespace

void* pool_allocate(size_t bytes) {
  const size_t size = rounded(bytes);
  if (size == 0) throw std::bad_alloc();
  Pool& pl = pool();
  {
    std::lock_guard<std::mutex> lock(pl.mutex);
    pl.drop_idle(Clock::now());
    for (size_t k = pl.held.size(); k-- > 0;) {
      if (pl.held[k].bytes != size) continue;
      void* p = pl.held[k].p;
      pl.held.erase(pl.held.begin() + static_cast<long>(k));
      pl.stats.held_bytes -= size;
      ++pl.stats.reused;
      return p;
    }
    ++pl.stats.allocated;
  }
  return fresh(size);
}

void pool_deallocate(void* p, size_t bytes) noexcept {
  if (!p) return;
  const size_t size = rounded(bytes);
  Pool& pl = pool();
  std::lock_guard<std::mutex> lock(pl.mutex);
  const auto now = Clock::now();
  pl.drop_idle(now);
  if (size > pl.stats.limit_bytes) {
    std::free(p);
    return;
  }
  try {
    pl.held.push_back({p, size, now});
  } catch (const std::bad_alloc&) {
    std::free(p);
    return;
  }
  pl.stats.held_bytes += size;
  pl.fit_limit();
}

void configure_buffer_pool(uint64_t limit_bytes, double max_idle_seconds) {
  if (!std::isfinite(max_idle_seconds) || max_idle_seconds < 0)
    throw InvalidArgument("max_idle_seconds", "expected a finite number of seconds >= 0");
  Pool& pl = pool();
  std::lock_guard<std::mutex> lock(pl.mutex);
  pl.stats.limit_bytes = limit_bytes;
  pl.stats.max_idle_seconds = max_idle_seconds;
  pl.fit_limit();
  pl.drop_idle(Clock::now());
}

BufferPoolStats buffer_pool_stats() {
  Pool& pl = pool();
  std::lock_guard<std::mutex> lock(pl.mutex);
  return pl.stats;
}

uint64_t trim_buffer_pool() {
  Pool& pl = pool();
  std::lock_guard<std::mutex> lock(pl.mutex);
  return pl.drop_idle(Clock::now());
}

uint64_t release_buffer_pool() {
  Pool& pl = pool();
  std::lock_guard<std::mutex> lock(pl.mutex);
  return pl.drop_while([](const Block&) { return true; });
}

}  // namespace glint
