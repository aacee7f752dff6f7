#include "sinew/postprocess/contact_sheet.hpp"

#include <algorithm>

#include "sinew/common/error.hpp"

namespace sinew::postprocess {

int contact_sheet_label_height(const ContactSheetOptions& o) {
  return text_height(o.font_scale) + o.padding;
}

Image contact_sheet(const std::vector<Image>& frames, const std::vector<std::string>& labels,
                    const ContactSheetOptions& o) {
  if (frames.empty()) throw ConfigError("", "contact sheet", "no frames");
  if (o.columns < 1) throw ConfigError("", "columns", "must be at least 1");
  const int w = frames.front().width, h = frames.front().height;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (frames[i].width != w || frames[i].height != h) {
      throw ConfigError("", "contact sheet", "frames of different sizes")
          .at(static_cast<std::int64_t>(i));
    }
  }
  const int n = static_cast<int>(frames.size());
  const int cols = std::min(o.columns, n), rows = (n + cols - 1) / cols;
  const int label_h = contact_sheet_label_height(o);
  const int tile_w = w + o.padding, tile_h = h + label_h + o.padding;
  Image sheet(cols * tile_w + o.padding, rows * tile_h + o.padding, o.background);
  for (int i = 0; i < n; ++i) {
    const int x = o.padding + (i % cols) * tile_w, y = o.padding + (i / cols) * tile_h;
    sheet.blit(frames[static_cast<std::size_t>(i)], x, y);
    if (static_cast<std::size_t>(i) < labels.size()) {
      const auto& text = labels[static_cast<std::size_t>(i)];
      const int tw = text_width(text, o.font_scale);
      draw_text(sheet, x + std::max(0, (w - tw) / 2), y + h + o.padding / 2, text, o.ink,
                o.font_scale);
    }
  }
  return sheet;
}

}  // namespace sinew::postprocess
