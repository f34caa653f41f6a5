#include "glint/png.h"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

#include "glint/errors.h"
#include "glint/options.h"

namespace glint {
namespace {

void put_u32(std::vector<unsigned char>& out, std::uint32_t v) {
  out.push_back(static_cast<unsigned char>(v >> 24));
  out.push_back(static_cast<unsigned char>(v >> 16));
  out.push_back(static_cast<unsigned char>(v >> 8));
  out.push_back(static_cast<unsigned char>(v));
}

void put_chunk(std::vector<unsigned char>& out, const char type[4], const unsigned char* data,
               size_t size) {
  put_u32(out, static_cast<std::uint32_t>(size));
  const size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  if (size) out.insert(out.end(), data, data + size);
  // The CRC covers the type and the data, not the length.
  uLong crc = crc32(0L, Z_NULL, 0);
  crc = crc32(crc, out.data() + start, static_cast<uInt>(out.size() - start));
  put_u32(out, static_cast<std::uint32_t>(crc));
}

}  // namespace

std::uint8_t linear_to_srgb8(float linear) {
  double v = linear;
  if (!(v > 0.0)) v = 0.0;  // also catches NaN
  if (v > 1.0) v = 1.0;
  const double e = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
  return static_cast<std::uint8_t>(std::lround(std::fmin(std::fmax(e, 0.0), 1.0) * 255.0));
}

void write_png_srgb(const std::string& path, const Image& img) {
  if (img.width < 1 || img.height < 1 || img.width > kMaxImageSide || img.height > kMaxImageSide ||
      img.data.size() != img.pixel_count() * 4)
    throw InvalidArgument("image", "expected a non-empty RGBA image of at most " +
                                       std::to_string(kMaxImageSide) + " pixels a side");
  const size_t stride = static_cast<size_t>(img.width) * 3 + 1;  // filter byte + RGB
  std::vector<unsigned char> raw(stride * static_cast<size_t>(img.height));
  for (int r = 0; r < img.height; ++r) {
    unsigned char* line = raw.data() + static_cast<size_t>(r) * stride;
    line[0] = 0;  // filter type None
    const int y = img.height - 1 - r;
    for (int x = 0; x < img.width; ++x) {
      const float* p = img.px(x, y);
      for (int c = 0; c < 3; ++c) line[1 + x * 3 + c] = linear_to_srgb8(p[c]);
    }
  }
  uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
  std::vector<unsigned char> packed(packed_size);
  if (compress2(packed.data(), &packed_size, raw.data(), static_cast<uLong>(raw.size()), 6) != Z_OK)
    throw Error("cannot write PNG \"" + path + "\": zlib compression failed");

  std::vector<unsigned char> out = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<unsigned char> ihdr;
  put_u32(ihdr, static_cast<std::uint32_t>(img.width));
  put_u32(ihdr, static_cast<std::uint32_t>(img.height));
  ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0});  // 8-bit, truecolour, deflate, filter 0, no interlace
  put_chunk(out, "IHDR", ihdr.data(), ihdr.size());
  const unsigned char intent = 0;  // perceptual
  put_chunk(out, "sRGB", &intent, 1);
  // Chunks hold at most 2^31 - 1 bytes; 1 MiB pieces stay far below that.
  constexpr size_t kPiece = size_t{1} << 20;
  for (size_t at = 0; at < packed_size; at += kPiece)
    put_chunk(out, "IDAT", packed.data() + at, std::min<size_t>(kPiece, packed_size - at));
  put_chunk(out, "IEND", nullptr, 0);

  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw Error("cannot write PNG \"" + path + "\": " + std::strerror(errno));
  const size_t n = std::fwrite(out.data(), 1, out.size(), f);
  const bool closed = std::fclose(f) == 0;
  if (n != out.size() || !closed) {
    std::error_code ec;
    std::filesystem::remove(path, ec);
    throw Error("cannot write PNG \"" + path + "\": short write");
  }
}

}  // namespace glint
