// A minimal 8-bit PNG writer for previews of linear images (zlib only).
#pragma once
#include <cstdint>
#include <string>

#include "glint/image.h"

namespace glint {

// Linear value -> 8-bit sRGB code: clamp to [0, 1] (NaN -> 0), the standard
// sRGB transfer function (12.92 v below 0.0031308, else 1.055 v^(1/2.4) - 0.055),
// rounded to the nearest of 0..255.
std::uint8_t linear_to_srgb8(float linear);

// Writes the RGB channels of `img` as an 8-bit sRGB PNG (colour type 2, with
// an sRGB chunk); alpha is dropped. PNG stores the top row first, so Image
// row height - 1 becomes the first PNG row. Throws InvalidArgument("image")
// for an empty image and glint::Error when the file cannot be written.
void write_png_srgb(const std::string& path, const Image& img);

}  // namespace glint
