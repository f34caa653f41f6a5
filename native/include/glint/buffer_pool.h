// Large buffers kept for the next call instead of going back to the system.
//
// A 1920x1080 frame allocates about 300 MB of images (G-buffers, the trace's
// pyramid and outputs), all of the same sizes every frame. Returned to the
// allocator, those pages are handed back to the kernel and the next frame
// faults them in again, each zeroed by the kernel first: in a 1080p Blender
// frame that was more than half of the rasterizer's time. Buffers of at least
// kPoolMinBytes go through this pool instead: freed, they are held (up to a
// limit, for a while) and handed to the next request of the same rounded size,
// as a GPU renderer keeps its render targets between frames. docs/hardening.md.
//
// The memory held is not part of any call's memory limit (glint/memory.h); it
// is at most limit_bytes and goes back to the system when it has sat unused
// for max_idle_seconds (checked on every allocation and release, and by
// trim_buffer_pool()), or at once with release_buffer_pool().
#pragma once
#include <cstddef>
#include <cstdint>

namespace glint {

// Smaller requests go straight to operator new: they are cheap to fault in.
constexpr size_t kPoolMinBytes = size_t{1} << 20;

struct BufferPoolStats {
  uint64_t held_bytes = 0;      // freed buffers kept for reuse
  uint64_t limit_bytes = 0;     // 0: the pool is off, every buffer is freed
  double max_idle_seconds = 0;  // a held buffer unused this long is freed
  uint64_t reused = 0;          // requests served from the pool, since the start
  uint64_t allocated = 0;       // requests that took new memory, since the start
};

// Throws std::bad_alloc like operator new. `bytes` must be passed back
// unchanged to pool_deallocate.
void* pool_allocate(size_t bytes);
void pool_deallocate(void* p, size_t bytes) noexcept;

// The defaults: limit min(1 GiB, 1/16 of physical memory), 120 s idle; the
// pool is off (limit 0) in builds with AddressSanitizer, which must see every
// free. Throws InvalidArgument for a negative or non-finite max_idle_seconds.
void configure_buffer_pool(uint64_t limit_bytes, double max_idle_seconds);
BufferPoolStats buffer_pool_stats();
// Frees the buffers idle for longer than max_idle_seconds; returns the bytes freed.
uint64_t trim_buffer_pool();
// Frees every held buffer; returns the bytes freed.
uint64_t release_buffer_pool();

}  // namespace glint
