#pragma once
// PNG files through libpng: 8-bit RGB, no interlacing.
#include <string>

#include "sinew/postprocess/image.hpp"

namespace sinew::postprocess {

// Writes `image` to `path`; throws IoError when the file cannot be written.
void write_png(const std::string& path, const Image& image);

// Reads a PNG (any bit depth / colour type libpng can convert) as 8-bit RGB (alpha dropped,
// composited on nothing). Throws IoError when the file cannot be opened, FormatError when it is
// not a readable PNG.
Image read_png(const std::string& path);

}  // namespace sinew::postprocess
