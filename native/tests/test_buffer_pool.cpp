// The buffer pool (glint/buffer_pool.h): freed large buffers come back to the
// next request of their rounded size, within the limit and the idle time, and
// an image asked to be filled is filled whatever the block held before.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>
#include <vector>

#include "glint/buffer_pool.h"
#include "glint/errors.h"
#include "glint/image.h"

namespace glint {
namespace {

constexpr uint64_t kMiB = uint64_t{1} << 20;

// Each test starts from an empty pool with known settings (the pool is a
// process-wide singleton; ctest runs each test in its own process, but a
// plain run of the binary does not).
class BufferPool : public ::testing::Test {
 protected:
  void SetUp() override {
    release_buffer_pool();
    configure_buffer_pool(64 * kMiB, 60.0);
  }
  void TearDown() override { release_buffer_pool(); }
};

TEST_F(BufferPool, FreedImageIsHandedToTheNextOfItsSize) {
  const float* first;
  {
    Image a = Image::uninitialized(1000, 1000);  // 16 MB
    first = a.data.data();
    EXPECT_EQ(buffer_pool_stats().held_bytes, 0u);
  }
  EXPECT_EQ(buffer_pool_stats().held_bytes, 8 * 2 * kMiB);  // rounded up to 2 MiB
  const uint64_t reused = buffer_pool_stats().reused;
  // 1001x1000 rounds to the same 16 MiB block.
  Image b = Image::uninitialized(1001, 1000);
  EXPECT_EQ(b.data.data(), first);
  EXPECT_EQ(buffer_pool_stats().reused, reused + 1);
  EXPECT_EQ(buffer_pool_stats().held_bytes, 0u);
}

TEST_F(BufferPool, BuffersStartOnHugePageBoundaries) {
  Image a = Image::uninitialized(640, 480);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(a.data.data()) % (2 * kMiB), 0u);
}

TEST_F(BufferPool, FilledImageIsFilledEvenFromAReusedBlock) {
  { Image dirty(1000, 1000, 7.0f); }
  Image clean(1000, 1000, 0.0f);
  for (float v : clean.data) ASSERT_EQ(v, 0.0f);
  EXPECT_GE(buffer_pool_stats().reused, 1u);
}

TEST_F(BufferPool, SmallBuffersBypassThePool) {
  const BufferPoolStats before = buffer_pool_stats();
  { Image small(100, 100); }  // 160 KB
  const BufferPoolStats after = buffer_pool_stats();
  EXPECT_EQ(after.held_bytes, 0u);
  EXPECT_EQ(after.allocated, before.allocated);
  EXPECT_EQ(after.reused, before.reused);
}

TEST_F(BufferPool, HoldsNoMoreThanItsLimitDroppingTheOldest) {
  configure_buffer_pool(40 * kMiB, 60.0);
  std::vector<const float*> order;
  {
    Image a = Image::uninitialized(1000, 1000), b = Image::uninitialized(1000, 1000),
          c = Image::uninitialized(1000, 1000);
    order = {a.data.data(), b.data.data(), c.data.data()};
    // Destroyed in reverse order: c, b, then a, which pushes c out.
  }
  EXPECT_EQ(buffer_pool_stats().held_bytes, 32 * kMiB);
  Image x = Image::uninitialized(1000, 1000), y = Image::uninitialized(1000, 1000);
  EXPECT_EQ(x.data.data(), order[0]);  // the most recently freed first
  EXPECT_EQ(y.data.data(), order[1]);
}

TEST_F(BufferPool, ABufferOverTheLimitIsFreedAtOnce) {
  configure_buffer_pool(4 * kMiB, 60.0);
  { Image a = Image::uninitialized(1000, 1000); }
  EXPECT_EQ(buffer_pool_stats().held_bytes, 0u);
  configure_buffer_pool(0, 60.0);  // off
  { Image a = Image::uninitialized(256, 256); }  // 1 MiB: pooled size, still freed
  EXPECT_EQ(buffer_pool_stats().held_bytes, 0u);
}

TEST_F(BufferPool, IdleBuffersAreTrimmed) {
  configure_buffer_pool(64 * kMiB, 0.0);
  { Image a = Image::uninitialized(1000, 1000); }
  std::this_thread::sleep_for(std::chrono::milliseconds(2));
  EXPECT_EQ(trim_buffer_pool(), 16 * kMiB);
  EXPECT_EQ(buffer_pool_stats().held_bytes, 0u);
  configure_buffer_pool(64 * kMiB, 60.0);
  { Image a = Image::uninitialized(1000, 1000); }
  EXPECT_EQ(trim_buffer_pool(), 0u);  // not idle long enough
  EXPECT_EQ(release_buffer_pool(), 16 * kMiB);
}

TEST_F(BufferPool, RejectsABadIdleTime) {
  EXPECT_THROW(configure_buffer_pool(kMiB, -1.0), InvalidArgument);
  EXPECT_THROW(configure_buffer_pool(kMiB, 1.0 / 0.0), InvalidArgument);
}

TEST_F(BufferPool, ThreadsShareItSafely) {
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([t] {
      for (int k = 0; k < 200; ++k) {
        Image a = Image::uninitialized(512 + 64 * ((k + t) % 5), 512);
        a.data.front() = a.data.back() = static_cast<float>(k);
      }
    });
  for (auto& th : threads) th.join();
  const BufferPoolStats s = buffer_pool_stats();
  EXPECT_LE(s.held_bytes, s.limit_bytes);
  EXPECT_EQ(release_buffer_pool(), s.held_bytes);
  EXPECT_EQ(buffer_pool_stats().held_bytes, 0u);
}

}  // namespace
}  // namespace glint
