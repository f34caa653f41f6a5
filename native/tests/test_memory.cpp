// The memory budget (glint/memory.h): the limit's sources, and requests over
// it refused before anything is allocated. Sizes expected here are counted
// from the outputs alone, a lower bound every estimate must reach.
#include <gtest/gtest.h>

#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "glint/exr.h"
#include "glint/marches.h"
#include "glint/memory.h"
#include "glint/raster.h"
#include "glint/stages.h"

namespace glint {
namespace {

constexpr int kSide = kMaxImageSide;
constexpr uint64_t kPixels = uint64_t(kSide) * kSide;

uint64_t peak_rss() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<uint64_t>(u.ru_maxrss) * 1024;
}

// Sets GLINT_MEMORY_LIMIT_MB for one test and restores it after.
class EnvLimit {
 public:
  explicit EnvLimit(const char* value) {
    if (const char* old = std::getenv(kMemoryLimitEnv)) old_ = old, had_ = true;
    if (value) setenv(kMemoryLimitEnv, value, 1);
    else unsetenv(kMemoryLimitEnv);
  }
  ~EnvLimit() {
    if (had_) setenv(kMemoryLimitEnv, old_.c_str(), 1);
    else unsetenv(kMemoryLimitEnv);
  }

 private:
  std::string old_;
  bool had_ = false;
};

TEST(MemoryLimit, DefaultIsHalfOfPhysicalMemory) {
  EnvLimit env(nullptr);
  const uint64_t phys = uint64_t(sysconf(_SC_PHYS_PAGES)) * uint64_t(sysconf(_SC_PAGE_SIZE));
  const MemoryLimit l = memory_limit();
  EXPECT_NEAR(double(l.bytes), double(phys) / 2, 1.0);
}

TEST(MemoryLimit, OptionBeatsVariableBeatsDefault) {
  EnvLimit env("300");
  EXPECT_EQ(memory_limit().bytes, 300ull << 20);
  EXPECT_EQ(memory_limit(2.5).bytes, uint64_t(2.5 * (1 << 20)));
  EXPECT_THROW(memory_limit(-1.0), InvalidArgument);
}

TEST(MemoryLimit, MalformedVariableIsNamed) {
  EnvLimit env("12abc");
  try {
    memory_limit();
    FAIL() << "accepted a malformed " << kMemoryLimitEnv;
  } catch (const InvalidArgument& e) {
    EXPECT_EQ(e.argument(), kMemoryLimitEnv);
  }
}

TEST(MemoryLimit, RefusalSaysWhatItNeededAndHowToRaiseIt) {
  try {
    require_memory(3ull << 30, "test request", 1024.0);
    FAIL() << "3 GiB passed a 1 GiB limit";
  } catch (const MemoryLimitExceeded& e) {
    EXPECT_EQ(e.needed_bytes(), 3ull << 30);
    EXPECT_EQ(e.limit_bytes(), 1ull << 30);
    const std::string msg = e.what();
    EXPECT_NE(msg.find("3.00 GiB"), std::string::npos) << msg;
    EXPECT_NE(msg.find("1.00 GiB"), std::string::npos) << msg;
    EXPECT_NE(msg.find("memory_limit_mb"), std::string::npos) << msg;
    EXPECT_NE(msg.find(kMemoryLimitEnv), std::string::npos) << msg;
  }
  EXPECT_NO_THROW(require_memory(1ull << 30, "test request", 1024.0));
}

TEST(MemoryEstimates, CoverTheOutputs) {
  for (const MarchInfo& m : march_table()) {
    EXPECT_GE(trace_bytes(kSide, kSide, m.id, false), 16 * kPixels) << m.name;
    EXPECT_GE(trace_bytes(kSide, kSide, m.id, true), 16 * kPixels) << m.name;
  }
  EXPECT_GE(raster_bytes(kSide, kSide, 0, false, false, false), 3 * 16 * kPixels);
  EXPECT_GE(raster_bytes(kSide, kSide, 0, true, false, false), 4 * 16 * kPixels);
  EXPECT_GE(raster_bytes(kSide, kSide, 0, true, true, false), 5 * 16 * kPixels);
  EXPECT_GE(raster_bytes(kSide, kSide, 0, true, true, true), 5 * 16 * kPixels);
  EXPECT_GT(raster_bytes(kSide, kSide, 0, true, true, true), raster_bytes(kSide, kSide, 0, true, false, true));
  EXPECT_GE(pipeline_bytes(kSide, kSide, PipelineOptions{}, false), 5 * 16 * kPixels);
  EXPECT_GE(exr_read_bytes(kSide, kSide, 3), 3 * 16 * kPixels);
}

TEST(MemoryBudget, CpuRasterizeAtTheLargestSizeIsRefusedBeforeAllocating) {
  EnvLimit env("4096");
  Mesh mesh;
  mesh.positions = {-1, -1, -3, 1, -1, -3, 0, 1, -3};
  mesh.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  mesh.material = {0};
  const std::vector<Material> mats(1);
  const std::vector<Image> maps;
  RasterInputs in{mesh, mats, maps, perspective(0.8, 1.0, 0.1, 100.0), kSide, kSide};
  const uint64_t before = peak_rss();
  auto cpu = make_cpu_backend(1);
  EXPECT_THROW(cpu->rasterize(in), MemoryLimitExceeded);
  EXPECT_LT(peak_rss() - before, 64ull << 20);
  // The same call with a limit it fits in runs.
  in.width = in.height = 8;
  EXPECT_EQ(cpu->rasterize(in).position.width, 8);
}

TEST(MemoryBudget, TraceRefusesOverTheOptionsLimit) {
  const Image pos(256, 256, 1.0f), nrm(256, 256, 0.0f);
  TraceInputs in{pos, nrm, nullptr, perspective(0.8, 1.0, 0.1, 100.0)};
  TraceOptions opt;
  opt.memory_limit_mb = 1.0;  // the output alone is 1 MiB at 256x256
  auto cpu = make_cpu_backend(1);
  EXPECT_THROW(cpu->trace(in, opt), MemoryLimitExceeded);
  opt.memory_limit_mb = 64.0;
  EXPECT_EQ(cpu->trace(in, opt).width, 256);
}

// A two-pixel EXR whose header promises a 32768x32768 picture: the reader sizes
// its layers by the display window, so before the check it zero-filled 16 GiB.
TEST(MemoryBudget, ExrHeaderPromisingGigabytesIsRefused) {
  const std::string path =
      (std::filesystem::temp_directory_path() / ("glint_liar_" + std::to_string(getpid()) + ".exr"))
          .string();
  {
    Imf::Header h(Imath::Box2i({0, 0}, {kSide - 1, kSide - 1}), Imath::Box2i({0, 0}, {1, 0}));
    h.channels().insert("R", Imf::Channel(Imf::FLOAT));
    Imf::OutputFile f(path.c_str(), h);
    float px[2] = {1.0f, 2.0f};
    Imf::FrameBuffer fb;
    fb.insert("R", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(px), sizeof(float), 0));
    f.setFrameBuffer(fb);
    f.writePixels(1);
  }
  EXPECT_LT(std::filesystem::file_size(path), 4096u);
  EnvLimit env(nullptr);  // the default: half of this machine's memory, under 16 GiB here
  const uint64_t before = peak_rss();
  if (memory_limit().bytes < 16 * kPixels) {
    EXPECT_THROW(read_exr(path), MemoryLimitExceeded);
  }
  EXPECT_THROW(read_exr(path, 1024.0), MemoryLimitExceeded);
  EXPECT_LT(peak_rss() - before, 64ull << 20);
  std::filesystem::remove(path);
}

// fuzz_exr's finding: OpenEXR allocates the size a header attribute declares
// before reading it, so 2 GB declared in a file of a few hundred bytes took
// 2 GB and seconds before the read failed. The reader now checks every
// declared size against the file first.
TEST(MemoryBudget, ExrAttributeLargerThanTheFileIsRefusedWithoutAllocating) {
  const std::string path =
      (std::filesystem::temp_directory_path() / ("glint_attr_" + std::to_string(getpid()) + ".exr"))
          .string();
  ExrWriteOptions wo;
  wo.options = "march=seed";
  wo.compression = "none";
  write_exr(path, {{"a", Image(2, 2, 1.0f)}}, wo);
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const std::string key = std::string("glintOptions") + '\0' + "string" + '\0';
  const size_t at = bytes.find(key);
  ASSERT_NE(at, std::string::npos);
  const uint32_t huge = 0x7ff00000u;  // 2 GiB, in a file of a few hundred bytes
  for (int k = 0; k < 4; ++k) bytes[at + key.size() + k] = static_cast<char>((huge >> (8 * k)) & 0xff);
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << bytes;
  }
  const uint64_t before = peak_rss();
  try {
    read_exr(path);
    FAIL() << "read a file whose header declares more bytes than it has";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("glintOptions"), std::string::npos) << e.what();
  }
  EXPECT_LT(peak_rss() - before, 64ull << 20);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace glint
