// Multilayer OpenEXR in and out: the pipeline's buffers as named layers of
// one file, with the camera projection in the header. No OpenEXR header is
// included here, so users of the core need none.
//
// Naming: a layer `position` is stored as the FLOAT channels `position.R`,
// `position.G`, `position.B`, `position.A`; the layer named "" as plain
// `R`, `G`, `B`, `A`. Rows: an Image keeps row 0 at the bottom, an EXR keeps
// the top scanline first; both functions flip, so Image row 0 is the bottom
// row of the picture in every viewer. See docs/exr.md for the reading rules.
#pragma once
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "glint/image.h"
#include "glint/projection.h"

namespace glint {

// Header attribute names, public so tools and docs quote the same strings.
constexpr const char* kExrProjectionAttribute = "glintProjection";  // m44d, rows as printed
constexpr const char* kExrOptionsAttribute = "glintOptions";        // string

struct ExrFile {
  // Layer name -> RGBA image (row 0 at the bottom), all the same size.
  std::map<std::string, Image> layers;
  // The glintProjection attribute when present: clip = projection * (x, y, z, 1).
  // Returned as stored (not validated): the consumer decides what it needs.
  std::optional<Mat4> projection;
  std::string options;      // the glintOptions attribute, "" when absent
  std::string compression;  // of the first part: "none", "zip", "piz", ...
  // Channels that map to no RGBA component (e.g. luminance-chroma "RY"),
  // reported instead of dropped silently.
  std::vector<std::string> skipped_channels;
};

struct ExrWriteOptions {
  std::optional<Mat4> projection;  // written as glintProjection when set
  std::string options;             // written as glintOptions when non-empty
  // Lossless methods only, since position/normal must round-trip exactly:
  // "none", "rle", "zips", "zip" (default), "piz".
  std::string compression = "zip";
};

// Reads a scanline or tiled, single- or multi-part EXR. Accepted channel
// names: `layer.R/G/B/A`, `layer.X/Y/Z/W`, `layer.x/y/z/w` (and lower-case
// r/g/b/a, U/V for 0/1); the layer is everything before the LAST dot, so
// Blender's `ViewLayer.Pass.R` gives layer `ViewLayer.Pass`; channels without
// a dot form the layer "". Missing R/G/B read as 0 and a missing A as 1 (as
// OpenEXR's own RGBA interface does); a layer made of a single channel (e.g.
// Blender's `ViewLayer.Depth.Z`) is broadcast to R, G and B with A = 1.
// HALF and FLOAT channels are read as float; UINT channels are an error.
// Throws InvalidArgument("path", ...) for a missing file, a file that is not
// an EXR, unsupported channel types or sampling, deep data and parts of
// different sizes; glint::Error for a file that fails while being read;
// MemoryLimitExceeded (glint/memory.h) when the layers the header announces
// would take more than memory_limit_mb (0: the default limit), checked
// before any pixel is allocated, since a few hundred bytes of header can
// promise gigabytes.
ExrFile read_exr(const std::string& path, double memory_limit_mb = 0.0);

// Writes every layer as four FLOAT channels (never HALF: positions and
// normals need all 24 bits). Throws InvalidArgument("layers", ...) for no
// layers, empty images or layers of different sizes, ("projection", ...) for
// a singular or non-finite projection, ("compression", ...) for an unknown or
// lossy method, and glint::Error when the file cannot be written.
void write_exr(const std::string& path, const std::map<std::string, Image>& layers,
               const ExrWriteOptions& options = {});

// Sizes OpenEXR's process-wide worker pool, where (de)compression runs;
// threads = 0: one per hardware thread. Process-wide on purpose and never
// called by the core itself: a host such as Blender shares the same OpenEXR
// library and sets its own pool. For programs that own their process.
void set_exr_threads(int threads);

}  // namespace glint
