// libFuzzer harness: glint::read_exr on arbitrary bytes. The reader takes a
// path, so the bytes go into an in-memory file (memfd) read through
// /proc/self/fd; nothing touches the disk. Any glint::Error is an answer;
// anything else escaping (an OpenEXR exception, a crash, a sanitizer report)
// is a finding.
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <string>

#include "glint/errors.h"
#include "glint/exr.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // Headers may promise huge images; the memory budget must refuse them
  // well under libFuzzer's 2 GB RSS limit, and small enough that a header
  // promising a large picture costs milliseconds, not a zero-filled gigabyte.
  setenv("GLINT_MEMORY_LIMIT_MB", "64", 1);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const int fd = memfd_create("glint-fuzz-exr", 0);
  if (fd < 0) std::abort();
  if (ftruncate(fd, 0) != 0 || pwrite(fd, data, size, 0) != static_cast<ssize_t>(size)) std::abort();
  static const std::string path = "/proc/self/fd/" + std::to_string(fd);
  try {
    glint::ExrFile f = glint::read_exr(path);
    // Touch every pixel so a layer that was sized but not filled shows up under MSan/ASan.
    float sum = 0.0f;
    for (const auto& [name, img] : f.layers)
      for (float v : img.data) sum += v;
    (void)sum;
  } catch (const glint::Error&) {
  }
  return 0;
}
