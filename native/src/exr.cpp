// Multilayer EXR reading and writing (see glint/exr.h for the rules).
//
// Pixels move through small strips of scanlines rather than whole-image
// frame buffers: the Image rows run bottom-up and EXR scanlines top-down, and
// OpenEXR's strides are unsigned, so a flipped view cannot be expressed as a
// slice. A strip costs one copy per row and keeps the extra memory to a few
// megabytes however large the image is.
#include "glint/exr.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfMatrixAttribute.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfThreading.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <set>
#include <thread>

#include "glint/errors.h"
#include "glint/memory.h"
#include "glint/options.h"

namespace glint {
namespace {

namespace fs = std::filesystem;

// Scratch budget for one strip, in floats: 4M floats = 16 MiB.
constexpr int64_t kStripFloats = int64_t{1} << 22;
constexpr int kMaxStripRows = 64;
constexpr size_t kMaxLayerNameLength = 250;  // EXR channel names stop at 255 bytes

std::string in_quotes(const std::string& s) { return "\"" + s + "\""; }

[[noreturn]] void bad_file(const std::string& path, const std::string& problem) {
  throw InvalidArgument("path", in_quotes(path) + ": " + problem);
}

// R/G/B/A and the vector spellings of the same slots; -1: not an RGBA slot.
int component_of(const std::string& suffix) {
  if (suffix.size() != 1) return -1;
  switch (suffix[0]) {
    case 'R': case 'r': case 'X': case 'x': case 'U': case 'u': return 0;
    case 'G': case 'g': case 'Y': case 'y': case 'V': case 'v': return 1;
    case 'B': case 'b': case 'Z': case 'z': return 2;
    case 'A': case 'a': case 'W': case 'w': return 3;
    default: return -1;
  }
}

const char* compression_name(Imf::Compression c) {
  switch (c) {
    case Imf::NO_COMPRESSION: return "none";
    case Imf::RLE_COMPRESSION: return "rle";
    case Imf::ZIPS_COMPRESSION: return "zips";
    case Imf::ZIP_COMPRESSION: return "zip";
    case Imf::PIZ_COMPRESSION: return "piz";
    case Imf::PXR24_COMPRESSION: return "pxr24";
    case Imf::B44_COMPRESSION: return "b44";
    case Imf::B44A_COMPRESSION: return "b44a";
    case Imf::DWAA_COMPRESSION: return "dwaa";
    case Imf::DWAB_COMPRESSION: return "dwab";
    default: return "unknown";
  }
}

Imf::Compression parse_compression(const std::string& name) {
  if (name == "none") return Imf::NO_COMPRESSION;
  if (name == "rle") return Imf::RLE_COMPRESSION;
  if (name == "zips") return Imf::ZIPS_COMPRESSION;
  if (name == "zip") return Imf::ZIP_COMPRESSION;
  if (name == "piz") return Imf::PIZ_COMPRESSION;
  throw InvalidArgument("compression", "expected a lossless method, \"none\", \"rle\", \"zips\", "
                                       "\"zip\" or \"piz\", got " + in_quotes(name));
}

// An OpenEXR output stream on a file descriptor that remembers any failed
// write. OpenEXR writes the line-offset table from OutputFile's destructor and
// swallows what goes wrong there, so success is only known from this flag,
// after the file object is gone.
class FdStream final : public Imf::OStream {
 public:
  FdStream(int fd, const std::string& name) : Imf::OStream(name.c_str()), fd_(fd) {}
  void write(const char c[], int n) override {
    while (n > 0) {
      const ssize_t k = ::pwrite(fd_, c, static_cast<size_t>(n), static_cast<off_t>(pos_));
      if (k < 0 && errno == EINTR) continue;
      if (k <= 0) {
        if (!error_) error_ = errno ? errno : EIO;
        throw std::runtime_error(std::strerror(error_));
      }
      c += k;
      n -= static_cast<int>(k);
      pos_ += static_cast<uint64_t>(k);
    }
  }
  uint64_t tellp() override { return pos_; }
  void seekp(uint64_t pos) override { pos_ = pos; }
  int error() const { return error_; }

 private:
  int fd_;
  uint64_t pos_ = 0;
  int error_ = 0;
};

// A name beside `path` for the file being written: same folder, so that the
// final rename never crosses a file system; hidden, and unique per process
// and call so that concurrent writers of one path never share it.
std::string temp_path_for(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  const fs::path p(path);
  const std::string name = "." + p.filename().string() + ".glint-tmp-" + std::to_string(::getpid()) +
                           "-" + std::to_string(counter++);
  return (p.parent_path() / name).string();
}

int strip_rows(int64_t width, int64_t floats_per_pixel) {
  const int64_t per_row = std::max<int64_t>(1, width * floats_per_pixel);
  return static_cast<int>(std::clamp<int64_t>(kStripFloats / per_row, 1, kMaxStripRows));
}

// Where a layer's components come from in one part: a channel index into the
// part's strip scratch, or -1 when the file lacks that component.
struct LayerSource {
  std::string name;
  int part = -1;
  std::array<int, 4> channel{-1, -1, -1, -1};
  std::array<std::string, 4> channel_name;
  int count = 0;
};

struct PartPlan {
  std::vector<std::string> channels;  // names read from this part, scratch order
  std::vector<LayerSource*> layers;
};

std::string size_text(const Imath::Box2i& w) {
  return std::to_string(int64_t{w.max.x} - w.min.x + 1) + "x" +
         std::to_string(int64_t{w.max.y} - w.min.y + 1);
}

void read_projection(const Imf::Header& h, const std::string& path, ExrFile& out) {
  auto it = h.find(kExrProjectionAttribute);
  if (it == h.end()) return;
  const Imf::Attribute& a = it.attribute();
  Mat4 m;
  if (auto* d = dynamic_cast<const Imf::M44dAttribute*>(&a)) {
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) m(r, c) = d->value()[r][c];
  } else if (auto* f = dynamic_cast<const Imf::M44fAttribute*>(&a)) {
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) m(r, c) = f->value()[r][c];
  } else {
    bad_file(path, std::string("header attribute ") + kExrProjectionAttribute + " has type " +
                       a.typeName() + ", expected m44d (a 4x4 double matrix)");
  }
  out.projection = m;
}

// A file whose structure is broken: it fails while being read (glint::Error,
// Python's RuntimeError), as OpenEXR's own parse errors do.
[[noreturn]] void corrupt(const std::string& path, const std::string& problem) {
  throw Error("cannot read EXR " + in_quotes(path) + ": " + problem);
}

// A NUL-terminated header string of at most 255 bytes (OpenEXR's longest name).
bool read_header_string(std::FILE* f, std::string& out) {
  out.clear();
  for (int c; (c = std::fgetc(f)) != EOF;) {
    if (c == 0) return true;
    if (out.size() == 255) return false;
    out.push_back(static_cast<char>(c));
  }
  return false;
}

// Bytes a value of a fixed-size attribute type takes; 0 for the types whose
// size the file states (strings, vectors, unknown types) and -1 for chlist and
// preview, which have their own layout.
int fixed_attribute_size(const std::string& type) {
  static const std::map<std::string, int> sizes = {
      {"box2i", 16},         {"box2f", 16}, {"compression", 1}, {"lineOrder", 1}, {"envmap", 1},
      {"deepImageState", 1}, {"int", 4},    {"float", 4},       {"double", 8},    {"v2i", 8},
      {"v2f", 8},            {"v2d", 16},   {"v3i", 12},        {"v3f", 12},      {"v3d", 24},
      {"m33f", 36},          {"m33d", 72},  {"m44f", 64},       {"m44d", 128},    {"chromaticities", 32},
      {"keycode", 28},       {"rational", 8}, {"timecode", 8},  {"tiledesc", 9},  {"chlist", -1},
      {"preview", -1}};
  const auto it = sizes.find(type);
  return it == sizes.end() ? 0 : it->second;
}

uint32_t read_u32(std::FILE* f, bool& ok) {
  unsigned char b[4];
  ok = ok && std::fread(b, 1, 4, f) == 4;
  return uint32_t{b[0]} | uint32_t{b[1]} << 8 | uint32_t{b[2]} << 16 | uint32_t{b[3]} << 24;
}

// OpenEXR reads a header attribute by allocating the size the file declares
// for it, before finding the file shorter: fuzz_exr found files of under 1 KB
// that made read_exr take 2 GB and seconds before failing. OpenEXR also reads
// fixed-size values and channel lists by their layout, not their declared
// size, so a wrong size shifts where it reads the next attribute. The headers
// (one, or one per part and an empty one after them) are walked here first:
// every size must be what the type takes and fit in what the file has left.
void check_header_sizes(std::FILE* f, const std::string& path) {
  if (std::fseek(f, 0, SEEK_END) != 0) corrupt(path, "cannot be read to its end");
  const int64_t file_size = std::ftell(f);
  unsigned char version[4];
  if (file_size < 8 || std::fseek(f, 4, SEEK_SET) != 0 || std::fread(version, 1, 4, f) != 4)
    corrupt(path, "is shorter than an OpenEXR header");
  const bool multipart = (version[1] & 0x10) != 0;  // flag bit 12 of the version field
  std::string name, type, channel;
  for (;;) {
    bool any = false;
    while (true) {
      if (!read_header_string(f, name)) corrupt(path, "header ends early or holds a name over 255 bytes");
      if (name.empty()) break;
      any = true;
      const std::string what = "header attribute " + in_quotes(name);
      bool ok = read_header_string(f, type);
      const int64_t size = static_cast<int32_t>(read_u32(f, ok));
      if (!ok) corrupt(path, what + " ends early");
      const int64_t start = std::ftell(f), left = file_size - start;
      if (size < 0 || size > left)
        corrupt(path, what + " declares " + std::to_string(size) + " bytes, but the file has " +
                          std::to_string(left) + " left");
      const int fixed = fixed_attribute_size(type);
      if (fixed > 0 && size != fixed)
        corrupt(path, what + " of type " + type + " declares " + std::to_string(size) +
                          " bytes, expected " + std::to_string(fixed));
      if (type == "chlist") {  // name, then type, pLinear, 3 reserved, x and y sampling
        while (read_header_string(f, channel) && !channel.empty() && std::fseek(f, 16, SEEK_CUR) == 0) {
        }
        if (std::ftell(f) - start != size)
          corrupt(path, what + " (a channel list) is not the " + std::to_string(size) +
                            " bytes it declares");
      } else if (type == "preview") {  // width, height, then 4 bytes a pixel
        bool pok = true;
        const uint64_t w = read_u32(f, pok), h = read_u32(f, pok);
        if (!pok || size < 8 || w * h * 4 != static_cast<uint64_t>(size - 8))
          corrupt(path, what + " (a preview image) is not the " + std::to_string(size) +
                            " bytes it declares");
      }
      std::fseek(f, static_cast<long>(start + size), SEEK_SET);
    }
    if (!multipart || !any) return;
  }
}

ExrFile read_exr_file(const std::string& path, double memory_limit_mb) {
  Imf::MultiPartInputFile file(path.c_str());
  const int parts = file.parts();
  if (parts < 1) bad_file(path, "holds no image parts");

  const Imath::Box2i display = file.header(0).displayWindow();
  const int64_t W = int64_t{display.max.x} - display.min.x + 1;
  const int64_t H = int64_t{display.max.y} - display.min.y + 1;
  if (W < 1 || H < 1 || W > kMaxImageSide || H > kMaxImageSide)
    bad_file(path, "display window is " + size_text(display) + ", expected 1 to " +
                       std::to_string(kMaxImageSide) + " pixels a side");

  ExrFile out;
  out.compression = compression_name(file.header(0).compression());
  std::map<std::string, LayerSource> sources;
  std::vector<PartPlan> plans(static_cast<size_t>(parts));
  for (int p = 0; p < parts; ++p) {
    const Imf::Header& h = file.header(p);
    if (h.hasType() && Imf::isDeepData(h.type()))
      bad_file(path, "part " + std::to_string(p) + " holds deep data, which is not supported");
    if (h.displayWindow() != display)
      bad_file(path, "part " + std::to_string(p) + " is " + size_text(h.displayWindow()) +
                         " but part 0 is " + size_text(display) +
                         "; all layers must have the same size");
    const Imath::Box2i dw = h.dataWindow();
    const int64_t dw_w = int64_t{dw.max.x} - dw.min.x + 1, dw_h = int64_t{dw.max.y} - dw.min.y + 1;
    if (dw_w < 1 || dw_h < 1 || dw_w > kMaxImageSide || dw_h > kMaxImageSide)
      bad_file(path, "data window of part " + std::to_string(p) + " is " + size_text(dw) +
                         ", expected 1 to " + std::to_string(kMaxImageSide) + " pixels a side");
    if (!out.projection) read_projection(h, path, out);
    if (out.options.empty()) {
      if (auto* s = h.findTypedAttribute<Imf::StringAttribute>(kExrOptionsAttribute))
        out.options = s->value();
    }

    for (auto it = h.channels().begin(); it != h.channels().end(); ++it) {
      const std::string name = it.name();
      const Imf::Channel& ch = it.channel();
      if (ch.type != Imf::HALF && ch.type != Imf::FLOAT)
        bad_file(path, "channel " + in_quotes(name) + " has type UINT, expected HALF or FLOAT");
      if (ch.xSampling != 1 || ch.ySampling != 1)
        bad_file(path, "channel " + in_quotes(name) + " is subsampled (" +
                           std::to_string(ch.xSampling) + "x" + std::to_string(ch.ySampling) +
                           "), which is not supported");
      const size_t dot = name.rfind('.');
      const std::string layer = dot == std::string::npos ? std::string() : name.substr(0, dot);
      const int comp = component_of(dot == std::string::npos ? name : name.substr(dot + 1));
      if (comp < 0) {
        out.skipped_channels.push_back(name);
        continue;
      }
      LayerSource& src = sources[layer];
      if (src.part < 0) {
        src.name = layer;
        src.part = p;
        plans[p].layers.push_back(&src);
      } else if (src.part != p) {
        bad_file(path, "layer " + in_quotes(layer) + " is split across parts " +
                           std::to_string(src.part) + " and " + std::to_string(p));
      }
      if (src.channel[comp] >= 0)
        bad_file(path, "channels " + in_quotes(src.channel_name[comp]) + " and " + in_quotes(name) +
                           " both give component " + std::string(1, "RGBA"[comp]) + " of layer " + in_quotes(layer));
      src.channel[comp] = static_cast<int>(plans[p].channels.size());
      src.channel_name[comp] = name;
      ++src.count;
      plans[p].channels.push_back(name);
    }
  }
  if (sources.empty())
    bad_file(path, "has no R/G/B/A or X/Y/Z/W channels (found " +
                       std::to_string(out.skipped_channels.size()) + " other channels)");

  require_memory(exr_read_bytes(W, H, sources.size()),
                 "reading " + in_quotes(path) + " (" + std::to_string(sources.size()) + " layers of " +
                     size_text(display) + ")",
                 memory_limit_mb);
  // Zero outside the data window ("nothing there"), defaults inside it.
  for (auto& [name, src] : sources) out.layers[name] = Image(static_cast<int>(W), static_cast<int>(H));

  for (int p = 0; p < parts; ++p) {
    const PartPlan& plan = plans[p];
    if (plan.channels.empty()) continue;
    Imf::InputPart part(file, p);
    const Imath::Box2i dw = file.header(p).dataWindow();
    const int64_t dw_w = int64_t{dw.max.x} - dw.min.x + 1;
    const int64_t nch = static_cast<int64_t>(plan.channels.size());
    const int rows = strip_rows(dw_w, nch);
    const size_t plane = static_cast<size_t>(rows) * static_cast<size_t>(dw_w);
    std::vector<float> scratch(plane * static_cast<size_t>(nch));

    for (int64_t y0 = dw.min.y; y0 <= dw.max.y; y0 += rows) {
      const int y1 = static_cast<int>(std::min<int64_t>(y0 + rows - 1, dw.max.y));
      const Imath::Box2i strip(Imath::V2i(dw.min.x, static_cast<int>(y0)), Imath::V2i(dw.max.x, y1));
      Imf::FrameBuffer fb;
      for (int64_t c = 0; c < nch; ++c) {
        fb.insert(plan.channels[c],
                  Imf::Slice::Make(Imf::FLOAT, scratch.data() + c * plane, strip, sizeof(float),
                                   sizeof(float) * static_cast<size_t>(dw_w)));
      }
      part.setFrameBuffer(fb);
      part.readPixels(static_cast<int>(y0), y1);

      for (int64_t y = y0; y <= y1; ++y) {
        const int64_t row = (H - 1) - (y - display.min.y);  // EXR top-down -> Image bottom-up
        if (row < 0 || row >= H) continue;
        const int64_t x_lo = std::max<int64_t>(dw.min.x, display.min.x);
        const int64_t x_hi = std::min<int64_t>(dw.max.x, display.max.x);
        const size_t line = static_cast<size_t>(y - y0) * static_cast<size_t>(dw_w);
        for (LayerSource* src : plan.layers) {
          Image& img = out.layers[src->name];
          // A lone colour or vector channel (a depth or mist pass) reads as grey.
          const int lone = (src->count == 1 && src->channel[3] < 0)
                               ? std::max({src->channel[0], src->channel[1], src->channel[2]})
                               : -1;
          for (int64_t x = x_lo; x <= x_hi; ++x) {
            float* px = img.px(static_cast<int>(x - display.min.x), static_cast<int>(row));
            const size_t at = line + static_cast<size_t>(x - dw.min.x);
            if (lone >= 0) {
              const float v = scratch[static_cast<size_t>(lone) * plane + at];
              px[0] = px[1] = px[2] = v;
              px[3] = 1.0f;
              continue;
            }
            for (int k = 0; k < 4; ++k) {
              const int c = src->channel[k];
              px[k] = c >= 0 ? scratch[static_cast<size_t>(c) * plane + at] : (k == 3 ? 1.0f : 0.0f);
            }
          }
        }
      }
    }
  }
  return out;
}

}  // namespace

ExrFile read_exr(const std::string& path, double memory_limit_mb) {
  if (path.empty()) throw InvalidArgument("path", "expected the name of an EXR file, got \"\"");
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) bad_file(path, "no such file");
  if (fs::is_directory(st)) bad_file(path, "is a directory, expected an EXR file");
  {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) bad_file(path, std::string("cannot be opened: ") + std::strerror(errno));
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> closer(f, &std::fclose);
    unsigned char magic[4] = {0, 0, 0, 0};
    const size_t n = std::fread(magic, 1, 4, f);
    // Every EXR starts with 76 2f 31 01; checking it first turns "some
    // other file" into a clear message instead of a library parse error.
    if (n != 4 || magic[0] != 0x76 || magic[1] != 0x2f || magic[2] != 0x31 || magic[3] != 0x01)
      bad_file(path, "is not an OpenEXR file (bad magic number)");
    check_header_sizes(f, path);
  }
  try {
    return read_exr_file(path, memory_limit_mb);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error("cannot read EXR " + in_quotes(path) + ": " + e.what());
  }
}

void write_exr(const std::string& path, const std::map<std::string, Image>& layers,
               const ExrWriteOptions& options) {
  if (path.empty()) throw InvalidArgument("path", "expected a file name to write, got \"\"");
  if (layers.empty()) throw InvalidArgument("layers", "expected at least one layer, got none");
  const Image& first = layers.begin()->second;
  for (const auto& [name, img] : layers) {
    const std::string arg = "layers[" + in_quotes(name) + "]";
    if (img.width < 1 || img.height < 1 || img.width > kMaxImageSide || img.height > kMaxImageSide)
      throw InvalidArgument(arg, "expected 1 to " + std::to_string(kMaxImageSide) +
                                     " pixels a side, got " + std::to_string(img.width) + "x" +
                                     std::to_string(img.height));
    if (img.data.size() != img.pixel_count() * 4)
      throw InvalidArgument(arg, "expected width * height * 4 floats, got " +
                                     std::to_string(img.data.size()));
    if (img.width != first.width || img.height != first.height)
      throw InvalidArgument(arg, "expected the size of every other layer, " +
                                     std::to_string(first.width) + "x" + std::to_string(first.height) +
                                     " (layer " + in_quotes(layers.begin()->first) + "), got " +
                                     std::to_string(img.width) + "x" + std::to_string(img.height));
    if (name.size() > kMaxLayerNameLength)
      throw InvalidArgument(arg, "expected a layer name of at most " +
                                     std::to_string(kMaxLayerNameLength) + " bytes");
  }
  if (options.projection) validate_projection(*options.projection);
  const Imf::Compression compression = parse_compression(options.compression);

  const int W = first.width, H = first.height;
  // Written to a temporary file in the same folder and renamed over `path`
  // only when complete and synced: a full disk, a failing write or a killed
  // process never leaves a truncated file under the final name (and an older
  // file there stays whole until the new one replaces it).
  const std::string tmp = temp_path_for(path);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0)
    throw Error("cannot write EXR " + in_quotes(path) + ": cannot create a file in its folder: " +
                std::strerror(errno));
  auto fail = [&](const std::string& why) {
    ::close(fd);
    ::unlink(tmp.c_str());
    throw Error("cannot write EXR " + in_quotes(path) + ": " + why);
  };
  FdStream stream(fd, tmp);
  try {
    Imf::Header header(W, H);
    header.compression() = compression;
    if (options.projection) {
      Imath::M44d m;
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m[r][c] = (*options.projection)(r, c);
      header.insert(kExrProjectionAttribute, Imf::M44dAttribute(m));
    }
    if (!options.options.empty())
      header.insert(kExrOptionsAttribute, Imf::StringAttribute(options.options));
    static const char* const kSuffix[4] = {"R", "G", "B", "A"};
    for (const auto& [name, img] : layers)
      for (const char* s : kSuffix)
        header.channels().insert(name.empty() ? std::string(s) : name + "." + s,
                                 Imf::Channel(Imf::FLOAT));

    Imf::OutputFile file(stream, header);
    const int rows = strip_rows(W, 4 * static_cast<int64_t>(layers.size()));
    const size_t row_floats = static_cast<size_t>(W) * 4;
    const size_t plane = row_floats * static_cast<size_t>(rows);
    std::vector<float> scratch(plane * layers.size());
    for (int y0 = 0; y0 < H; y0 += rows) {
      const int y1 = std::min(y0 + rows - 1, H - 1);
      const Imath::Box2i strip(Imath::V2i(0, y0), Imath::V2i(W - 1, y1));
      Imf::FrameBuffer fb;
      size_t k = 0;
      for (const auto& [name, img] : layers) {
        float* base = scratch.data() + k++ * plane;
        for (int y = y0; y <= y1; ++y)  // EXR scanline y is Image row H - 1 - y
          std::memcpy(base + static_cast<size_t>(y - y0) * row_floats, img.px(0, H - 1 - y),
                      row_floats * sizeof(float));
        for (int c = 0; c < 4; ++c)
          fb.insert(name.empty() ? std::string(kSuffix[c]) : name + "." + kSuffix[c],
                    Imf::Slice::Make(Imf::FLOAT, base + c, strip, 4 * sizeof(float),
                                     row_floats * sizeof(float)));
      }
      file.setFrameBuffer(fb);
      file.writePixels(y1 - y0 + 1);
    }
  } catch (const std::exception& e) {
    fail(stream.error() ? std::strerror(stream.error()) : e.what());
  }
  if (stream.error()) fail(std::strerror(stream.error()));  // the offset table, written on close
  if (::fsync(fd) != 0) fail(std::string("fsync: ") + std::strerror(errno));
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw Error("cannot write EXR " + in_quotes(path) + ": close: " + std::strerror(err));
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw Error("cannot write EXR " + in_quotes(path) + ": " + std::strerror(err));
  }
}

void set_exr_threads(int threads) {
  validate_threads(threads);
  if (threads == 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  Imf::setGlobalThreadCount(threads);
}

}  // namespace glint
