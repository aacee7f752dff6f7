#pragma once
// An 8-bit RGB image in memory and a tiny built-in 5 × 7 bitmap font for labels (digits, the
// letters A–Z (lower case drawn as upper case) and . , - + = : / ( ) % | _ and space).
#include <cstdint>
#include <string>
#include <vector>

namespace sinew::postprocess {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb&) const = default;
};

// Row-major, row 0 at the top, 3 bytes (R, G, B) per pixel: height × width × 3.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> pixels;

  Image() = default;
  Image(int w, int h, Rgb fill = {255, 255, 255});
  Rgb at(int x, int y) const;
  void set(int x, int y, Rgb c);  // ignores pixels outside the image
  void fill_rect(int x, int y, int w, int h, Rgb c);
  // Copies `src` with its top-left corner at (x, y), clipped to this image.
  void blit(const Image& src, int x, int y);
};

// The w × h pixels of `image` from column x, row y (top left). Throws ConfigError (field "--crop")
// when the rectangle is empty or not inside the image.
Image crop(const Image& image, int x, int y, int w, int h);

// Glyphs are 5 × 7 cells with one cell of spacing, each cell `scale` × `scale` pixels.
int text_width(const std::string& text, int scale);
inline int text_height(int scale) {
  return 7 * scale;
}
// Draws `text` with its top-left corner at (x, y); characters without a glyph draw as a box.
void draw_text(Image& image, int x, int y, const std::string& text, Rgb color, int scale);

}  // namespace sinew::postprocess
