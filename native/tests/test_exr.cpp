// EXR and PNG I/O. Orientation and attributes are checked against files read
// or written with OpenEXR directly (and a PNG inflated with zlib), so a bug
// made twice, once in the writer and once in the reader, cannot cancel out.
#include <gtest/gtest.h>

#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfMatrixAttribute.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <zlib.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "glint/errors.h"
#include "glint/exr.h"
#include "glint/png.h"

using namespace glint;
namespace fs = std::filesystem;

namespace {

class TempDir {
 public:
  TempDir() {
    dir_ = fs::temp_directory_path() /
           ("glint_test_exr_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

 private:
  fs::path dir_;
};

// Every pixel different, so a flip, a shift or a channel swap shows.
Image ramp(int w, int h, float offset) {
  Image img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 4; ++c) img.px(x, y)[c] = offset + 1000.0f * c + 10.0f * y + 0.5f * x;
  return img;
}

// Writes named FLOAT/HALF/UINT channels with OpenEXR directly; `top_first`
// holds, per channel, W*H values with the TOP scanline first (EXR order).
struct RawChannel {
  std::string name;
  Imf::PixelType type;
  std::vector<float> top_first;
};

void write_raw(const std::string& path, int w, int h, const std::vector<RawChannel>& channels) {
  Imf::Header header(w, h);
  for (const auto& ch : channels) header.channels().insert(ch.name, Imf::Channel(ch.type));
  Imf::FrameBuffer fb;
  std::vector<std::vector<unsigned>> uints;
  std::vector<std::vector<Imath::half>> halves;
  uints.reserve(channels.size());
  halves.reserve(channels.size());
  for (const auto& ch : channels) {
    if (ch.type == Imf::HALF) {
      halves.emplace_back(ch.top_first.begin(), ch.top_first.end());
      fb.insert(ch.name, Imf::Slice(Imf::HALF, reinterpret_cast<char*>(halves.back().data()),
                                    sizeof(Imath::half), sizeof(Imath::half) * w));
    } else if (ch.type == Imf::UINT) {
      uints.emplace_back(ch.top_first.begin(), ch.top_first.end());
      fb.insert(ch.name, Imf::Slice(Imf::UINT, reinterpret_cast<char*>(uints.back().data()),
                                    sizeof(unsigned), sizeof(unsigned) * w));
    } else {
      fb.insert(ch.name, Imf::Slice(Imf::FLOAT, const_cast<char*>(reinterpret_cast<const char*>(
                                                    ch.top_first.data())),
                                    sizeof(float), sizeof(float) * w));
    }
  }
  Imf::OutputFile out(path.c_str(), header);
  out.setFrameBuffer(fb);
  out.writePixels(h);
}

// One channel of an EXR, read with OpenEXR directly, top scanline first.
std::vector<float> read_raw(const std::string& path, const std::string& channel) {
  Imf::InputFile in(path.c_str());
  const Imath::Box2i dw = in.header().dataWindow();
  const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
  std::vector<float> v(static_cast<size_t>(w) * h, -12345.0f);
  Imf::FrameBuffer fb;
  fb.insert(channel, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(v.data()), sizeof(float),
                                sizeof(float) * w, 1, 1, -999.0));
  in.setFrameBuffer(fb);
  in.readPixels(dw.min.y, dw.max.y);
  return v;
}

template <class E, class F>
std::string message_of(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "<no exception>";
}

}  // namespace

TEST(Exr, RoundTripKeepsEveryPixelExactly) {
  TempDir tmp;
  const std::string path = tmp.file("round.exr");
  std::map<std::string, Image> layers = {{"position", ramp(7, 5, 0.25f)},
                                         {"normal", ramp(7, 5, -3.0f)}};
  layers["position"].px(2, 3)[1] = std::numeric_limits<float>::quiet_NaN();  // data, not an error
  layers["normal"].px(6, 4)[0] = 1.0f + 1.0f / 8388608.0f;  // needs all 24 bits: no HALF
  write_exr(path, layers);
  const ExrFile f = read_exr(path);
  ASSERT_EQ(f.layers.size(), 2u);
  EXPECT_EQ(f.compression, "zip");
  EXPECT_FALSE(f.projection.has_value());
  EXPECT_TRUE(f.skipped_channels.empty());
  for (const auto& [name, img] : layers) {
    const Image& got = f.layers.at(name);
    ASSERT_EQ(got.width, 7);
    ASSERT_EQ(got.height, 5);
    for (size_t i = 0; i < img.data.size(); ++i) {
      if (std::isnan(img.data[i]))
        EXPECT_TRUE(std::isnan(got.data[i])) << name << " " << i;
      else
        EXPECT_EQ(got.data[i], img.data[i]) << name << " " << i;
    }
  }
}

TEST(Exr, WriterPutsTheBottomRowLastInTheFile) {
  TempDir tmp;
  const std::string path = tmp.file("orient.exr");
  Image img(3, 4, 0.0f);
  img.px(0, 0)[0] = 7.0f;   // bottom-left
  img.px(2, 3)[2] = -5.0f;  // top-right
  write_exr(path, {{"position", img}});
  const auto r = read_raw(path, "position.R");
  const auto b = read_raw(path, "position.B");
  // EXR scanline 0 is the top of the picture: bottom-left is the last line's first pixel.
  EXPECT_EQ(r[3 * 3 + 0], 7.0f);
  EXPECT_EQ(r[0], 0.0f);
  EXPECT_EQ(b[0 * 3 + 2], -5.0f);
  EXPECT_EQ(b[3 * 3 + 2], 0.0f);
  Imf::InputFile in(path.c_str());
  EXPECT_EQ(in.header().compression(), Imf::ZIP_COMPRESSION);
  EXPECT_EQ(in.header().channels().findChannel("position.A")->type, Imf::FLOAT);
}

TEST(Exr, ReaderPutsTheFirstScanlineOnTop) {
  TempDir tmp;
  const std::string path = tmp.file("top.exr");
  // 2x3, top scanline first: the value 9 sits at the top-left.
  write_raw(path, 2, 3, {{"color.R", Imf::FLOAT, {9, 0, 0, 0, 0, 4}},
                         {"color.B", Imf::FLOAT, {0, 0, 0, 0, 0, 0}}});
  const ExrFile f = read_exr(path);
  const Image& c = f.layers.at("color");
  EXPECT_EQ(c.px(0, 2)[0], 9.0f);  // row 2 = top
  EXPECT_EQ(c.px(1, 0)[0], 4.0f);  // row 0 = bottom
  EXPECT_EQ(c.px(0, 0)[0], 0.0f);
  // Missing G reads 0, missing A reads 1 (OpenEXR's own RGBA convention).
  EXPECT_EQ(c.px(0, 2)[1], 0.0f);
  EXPECT_EQ(c.px(0, 2)[3], 1.0f);
}

TEST(Exr, ProjectionAndOptionsAttributesRoundTrip) {
  TempDir tmp;
  const std::string path = tmp.file("proj.exr");
  Mat4 p = perspective(0.8, 16.0 / 9.0, 0.1, 100.0);
  p(0, 2) = 0.125;  // a lens shift: makes the matrix non-symmetric in its layout
  ExrWriteOptions opt;
  opt.projection = p;
  opt.options = "max_distance=15 march=seed";
  write_exr(path, {{"uv", Image(2, 2, 0.5f)}}, opt);

  const ExrFile f = read_exr(path);
  ASSERT_TRUE(f.projection.has_value());
  for (int i = 0; i < 16; ++i) EXPECT_EQ(f.projection->m[i], p.m[i]) << i;
  EXPECT_EQ(f.options, "max_distance=15 march=seed");

  // Stored rows as printed: row 3 is (0, 0, -1, 0) for a perspective camera.
  Imf::InputFile in(path.c_str());
  const auto* a = in.header().findTypedAttribute<Imf::M44dAttribute>(kExrProjectionAttribute);
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(a->value()[3][2], -1.0);
  EXPECT_EQ(a->value()[3][3], 0.0);
  EXPECT_EQ(a->value()[0][2], 0.125);
  const auto* s = in.header().findTypedAttribute<Imf::StringAttribute>(kExrOptionsAttribute);
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->value(), "max_distance=15 march=seed");
}

TEST(Exr, ReadsBlenderAndVectorChannelNames) {
  TempDir tmp;
  const std::string path = tmp.file("blender.exr");
  const std::vector<float> one = {1, 2}, two = {3, 4}, three = {5, 6};
  write_raw(path, 2, 1,
            {{"ViewLayer.Combined.R", Imf::HALF, one},
             {"ViewLayer.Combined.G", Imf::HALF, two},
             {"ViewLayer.Combined.B", Imf::HALF, three},
             {"ViewLayer.Combined.A", Imf::HALF, {0.5f, 0.25f}},
             {"ViewLayer.Normal.X", Imf::FLOAT, one},
             {"ViewLayer.Normal.Y", Imf::FLOAT, two},
             {"ViewLayer.Normal.Z", Imf::FLOAT, three},
             {"ViewLayer.Depth.Z", Imf::FLOAT, {7, 8}},
             {"position.x", Imf::FLOAT, one},
             {"position.y", Imf::FLOAT, two},
             {"position.z", Imf::FLOAT, three},
             {"position.w", Imf::FLOAT, {0, 1}},
             {"R", Imf::FLOAT, {11, 12}},
             {"RY", Imf::FLOAT, {0, 0}}});
  const ExrFile f = read_exr(path);
  ASSERT_EQ(f.layers.size(), 5u);
  const float* c = f.layers.at("ViewLayer.Combined").px(1, 0);
  EXPECT_EQ(c[0], 2.0f);
  EXPECT_EQ(c[1], 4.0f);
  EXPECT_EQ(c[2], 6.0f);
  EXPECT_EQ(c[3], 0.25f);
  const float* n = f.layers.at("ViewLayer.Normal").px(0, 0);
  EXPECT_EQ(n[0], 1.0f);
  EXPECT_EQ(n[1], 3.0f);
  EXPECT_EQ(n[2], 5.0f);
  EXPECT_EQ(n[3], 1.0f);
  const float* d = f.layers.at("ViewLayer.Depth").px(1, 0);  // one channel: grey
  EXPECT_EQ(d[0], 8.0f);
  EXPECT_EQ(d[1], 8.0f);
  EXPECT_EQ(d[2], 8.0f);
  EXPECT_EQ(d[3], 1.0f);
  const float* p = f.layers.at("position").px(0, 0);
  EXPECT_EQ(p[0], 1.0f);
  EXPECT_EQ(p[2], 5.0f);
  EXPECT_EQ(p[3], 0.0f);
  EXPECT_EQ(f.layers.at("").px(1, 0)[0], 12.0f);
  ASSERT_EQ(f.skipped_channels.size(), 1u);
  EXPECT_EQ(f.skipped_channels[0], "RY");
}

TEST(Exr, MissingAndForeignFilesAreNamedInTheError) {
  TempDir tmp;
  const std::string missing = tmp.file("nope.exr");
  std::string msg = message_of<InvalidArgument>([&] { read_exr(missing); });
  EXPECT_NE(msg.find(missing), std::string::npos) << msg;
  EXPECT_NE(msg.find("no such file"), std::string::npos) << msg;

  const std::string text = tmp.file("text.exr");
  std::ofstream(text) << "this is not an image";
  msg = message_of<InvalidArgument>([&] { read_exr(text); });
  EXPECT_NE(msg.find("not an OpenEXR file"), std::string::npos) << msg;

  msg = message_of<InvalidArgument>([&] { read_exr(tmp.file("")); });
  EXPECT_NE(msg.find("directory"), std::string::npos) << msg;
}

TEST(Exr, TruncatedFileIsAnErrorNotACrash) {
  TempDir tmp;
  const std::string path = tmp.file("cut.exr");
  write_exr(path, {{"a", ramp(64, 64, 1.0f)}}, ExrWriteOptions{{}, "", "none"});
  fs::resize_file(path, fs::file_size(path) / 2);
  const std::string msg = message_of<Error>([&] { read_exr(path); });
  EXPECT_NE(msg.find(path), std::string::npos) << msg;
}

TEST(Exr, UintChannelsAreRejected) {
  TempDir tmp;
  const std::string path = tmp.file("ids.exr");
  write_raw(path, 2, 1, {{"id.R", Imf::UINT, {1, 2}}});
  const std::string msg = message_of<InvalidArgument>([&] { read_exr(path); });
  EXPECT_NE(msg.find("id.R"), std::string::npos) << msg;
  EXPECT_NE(msg.find("UINT"), std::string::npos) << msg;
}

TEST(Exr, WriterRejectsBadLayers) {
  TempDir tmp;
  const std::string path = tmp.file("bad.exr");
  auto arg = [](auto&& f) {
    try {
      f();
    } catch (const InvalidArgument& e) {
      return e.argument();
    }
    return std::string("<none>");
  };
  EXPECT_EQ(arg([&] { write_exr(path, {}); }), "layers");
  EXPECT_EQ(arg([&] { write_exr(path, {{"a", Image(2, 2)}, {"b", Image(3, 2)}}); }),
            "layers[\"b\"]");
  EXPECT_EQ(arg([&] { write_exr(path, {{"a", Image()}}); }), "layers[\"a\"]");
  ExrWriteOptions singular;
  singular.projection = Mat4{};
  EXPECT_EQ(arg([&] { write_exr(path, {{"a", Image(2, 2)}}, singular); }), "projection");
  ExrWriteOptions lossy;
  lossy.compression = "b44";
  EXPECT_EQ(arg([&] { write_exr(path, {{"a", Image(2, 2)}}, lossy); }), "compression");
  EXPECT_FALSE(fs::exists(path));
  // A directory that does not exist: a glint::Error naming the file.
  const std::string nowhere = tmp.file("no/such/dir.exr");
  const std::string msg = message_of<Error>([&] { write_exr(nowhere, {{"a", Image(2, 2)}}); });
  EXPECT_NE(msg.find(nowhere), std::string::npos) << msg;
}

TEST(Png, SrgbEncodingMatchesHandValues) {
  EXPECT_EQ(linear_to_srgb8(0.0f), 0);
  EXPECT_EQ(linear_to_srgb8(1.0f), 255);
  EXPECT_EQ(linear_to_srgb8(0.001f), 3);   // linear segment: 12.92 * 0.001 * 255 = 3.29
  EXPECT_EQ(linear_to_srgb8(0.18f), 118);  // (1.055 * 0.18^(1/2.4) - 0.055) * 255 = 117.65
  EXPECT_EQ(linear_to_srgb8(0.5f), 188);   // 187.52
  EXPECT_EQ(linear_to_srgb8(-2.0f), 0);
  EXPECT_EQ(linear_to_srgb8(7.0f), 255);
  EXPECT_EQ(linear_to_srgb8(std::numeric_limits<float>::quiet_NaN()), 0);
  EXPECT_EQ(linear_to_srgb8(std::numeric_limits<float>::infinity()), 255);
}

TEST(Png, FileDecodesToTheImageTopRowFirst) {
  TempDir tmp;
  const std::string path = tmp.file("out.png");
  Image img(3, 2, 0.0f);
  img.px(0, 0)[0] = 1.0f;   // bottom-left red
  img.px(2, 1)[2] = 0.18f;  // top-right blue
  write_png_srgb(path, img);

  std::ifstream in(path, std::ios::binary);
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 33u);
  const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  ASSERT_TRUE(std::equal(sig, sig + 8, bytes.begin()));
  auto u32 = [&](size_t at) {
    return (uint32_t{bytes[at]} << 24) | (uint32_t{bytes[at + 1]} << 16) |
           (uint32_t{bytes[at + 2]} << 8) | bytes[at + 3];
  };
  std::vector<unsigned char> idat;
  uint32_t width = 0, height = 0;
  for (size_t at = 8; at + 12 <= bytes.size();) {
    const uint32_t len = u32(at);
    const std::string type(bytes.begin() + at + 4, bytes.begin() + at + 8);
    const uLong crc = crc32(crc32(0L, Z_NULL, 0), bytes.data() + at + 4, len + 4);
    EXPECT_EQ(crc, u32(at + 8 + len)) << type;
    if (type == "IHDR") {
      width = u32(at + 8);
      height = u32(at + 12);
      EXPECT_EQ(bytes[at + 16], 8);  // bit depth
      EXPECT_EQ(bytes[at + 17], 2);  // truecolour
    }
    if (type == "IDAT") idat.insert(idat.end(), bytes.begin() + at + 8, bytes.begin() + at + 8 + len);
    at += 12 + len;
  }
  ASSERT_EQ(width, 3u);
  ASSERT_EQ(height, 2u);
  std::vector<unsigned char> raw(2 * (1 + 3 * 3));
  uLongf raw_size = raw.size();
  ASSERT_EQ(uncompress(raw.data(), &raw_size, idat.data(), idat.size()), Z_OK);
  ASSERT_EQ(raw_size, raw.size());
  // PNG row 0 is the top: its last pixel is the blue one.
  EXPECT_EQ(raw[0], 0);
  EXPECT_EQ(raw[1 + 2 * 3 + 2], 118);
  EXPECT_EQ(raw[1 + 0], 0);
  // PNG row 1 is the bottom: its first pixel is the red one.
  EXPECT_EQ(raw[10 + 1 + 0], 255);
  EXPECT_EQ(raw[10 + 1 + 2], 0);
}
