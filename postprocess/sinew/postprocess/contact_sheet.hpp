#pragma once
// A contact sheet: several frames tiled row by row into one image, each with a label under it.
#include <string>
#include <vector>

#include "sinew/postprocess/image.hpp"

namespace sinew::postprocess {

struct ContactSheetOptions {
  int columns = 4;
  int padding = 8;  // pixels around and between tiles
  Rgb background{255, 255, 255};
  Rgb ink{20, 20, 20};
  int font_scale = 2;  // label glyph cell size, pixels
};

// Tiles `frames` (all of one size) into ceil(n / columns) rows; labels[i] (may be shorter than
// frames, missing labels are empty) is drawn under frame i. The result is
// (columns' × (w + padding) + padding) × (rows × (h + label height + padding) + padding) pixels,
// columns' = min(columns, n). Throws ConfigError on no frames, mixed sizes or columns < 1.
Image contact_sheet(const std::vector<Image>& frames, const std::vector<std::string>& labels,
                    const ContactSheetOptions& options = {});

// The height of a tile's label band: the glyph height plus padding.
int contact_sheet_label_height(const ContactSheetOptions& options);

}  // namespace sinew::postprocess
