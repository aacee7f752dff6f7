#include "sinew/postprocess/png_writer.hpp"

#include <png.h>

#include <cerrno>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"

namespace sinew::postprocess {
namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

// libpng reports errors by longjmp; the handler keeps the message (library code never prints) and
// jumps back into the small functions below, which hold no C++ objects across setjmp.
struct Context {
  char message[256] = "libpng error";
};
[[noreturn]] void on_error(png_structp png, png_const_charp message) {
  auto* ctx = static_cast<Context*>(png_get_error_ptr(png));
  if (ctx && message) std::snprintf(ctx->message, sizeof ctx->message, "%s", message);
  png_longjmp(png, 1);
}
void on_warning(png_structp, png_const_charp) {}

// A libpng read or write struct with its info struct and the context its errors go to, destroyed
// together. Throws IoError naming `path` when libpng runs out of memory.
struct PngStructs {
  enum class Mode { read, write };
  PngStructs(Mode m, const std::string& path) : mode(m) {
    png = mode == Mode::write
              ? png_create_write_struct(PNG_LIBPNG_VER_STRING, &ctx, on_error, on_warning)
              : png_create_read_struct(PNG_LIBPNG_VER_STRING, &ctx, on_error, on_warning);
    if (png) info = png_create_info_struct(png);
    if (!info) {
      destroy();
      throw IoError(path, "", "libpng: out of memory");
    }
  }
  ~PngStructs() { destroy(); }
  PngStructs(const PngStructs&) = delete;
  PngStructs& operator=(const PngStructs&) = delete;

  void destroy() {
    if (!png) return;
    if (mode == Mode::write) {
      png_destroy_write_struct(&png, &info);
    } else {
      png_destroy_read_struct(&png, &info, nullptr);
    }
  }

  const Mode mode;
  Context ctx;
  png_structp png = nullptr;
  png_infop info = nullptr;
};

bool write_all(png_structp png, png_infop info, std::FILE* f, const Image* image) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_init_io(png, f);
  png_set_IHDR(png, info, static_cast<png_uint_32>(image->width),
               static_cast<png_uint_32>(image->height), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < image->height; ++y) {
    png_write_row(png, image->pixels.data() + static_cast<std::size_t>(y) * image->width * 3);
  }
  png_write_end(png, nullptr);
  return true;
}

// Reads the header and sets up conversion to 8-bit RGB; the size lands in *w, *h.
bool read_header(png_structp png, png_infop info, std::FILE* f, png_uint_32* w, png_uint_32* h,
                 std::size_t* rowbytes) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_init_io(png, f);
  png_set_sig_bytes(png, 8);
  png_read_info(png, info);
  const auto type = png_get_color_type(png, info);
  if (png_get_bit_depth(png, info) == 16) png_set_strip_16(png);
  if (type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (type == PNG_COLOR_TYPE_GRAY || type == PNG_COLOR_TYPE_GRAY_ALPHA) {
    png_set_expand_gray_1_2_4_to_8(png);
    png_set_gray_to_rgb(png);
  }
  if (type & PNG_COLOR_MASK_ALPHA) png_set_strip_alpha(png);
  png_read_update_info(png, info);
  *w = png_get_image_width(png, info);
  *h = png_get_image_height(png, info);
  *rowbytes = png_get_rowbytes(png, info);
  return true;
}

bool read_rows(png_structp png, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_image(png, rows);
  png_read_end(png, nullptr);
  return true;
}

}  // namespace

void write_png(const std::string& path, const Image& image) {
  write_atomically(path, [&](const std::string& tmp) {
    File f(std::fopen(tmp.c_str(), "wb"));
    if (!f) throw IoError(path, "", "cannot open for writing: " + write_failure(errno));
    PngStructs p(PngStructs::Mode::write, path);
    errno = 0;
    if (!write_all(p.png, p.info, f.get(), &image)) {
      // libpng says only "Write Error" for a failed fwrite; errno tells a full disk apart.
      const std::string why = errno != 0 ? write_failure(errno) : p.ctx.message;
      throw IoError(path, "", "cannot write the PNG: " + why);
    }
    if (std::fflush(f.get()) != 0 || std::fclose(f.release()) != 0) {
      throw IoError(path, "", "cannot write: " + write_failure(errno));
    }
  });
}

Image read_png(const std::string& path) {
  File f(std::fopen(path.c_str(), "rb"));
  if (!f) throw IoError(path, "", "cannot open for reading");
  unsigned char sig[8] = {};
  if (std::fread(sig, 1, 8, f.get()) != 8 || png_sig_cmp(sig, 0, 8) != 0) {
    throw FormatError(path, "", "not a PNG file");
  }
  PngStructs p(PngStructs::Mode::read, path);
  png_uint_32 w = 0, h = 0;
  std::size_t rowbytes = 0;
  if (!read_header(p.png, p.info, f.get(), &w, &h, &rowbytes)) {
    throw FormatError(path, "", std::string("unreadable PNG: ") + p.ctx.message);
  }
  if (rowbytes != static_cast<std::size_t>(w) * 3 || w == 0 || h == 0 || w > 65536 || h > 65536) {
    throw FormatError(path, "", "unsupported PNG layout");
  }
  Image img(static_cast<int>(w), static_cast<int>(h));
  std::vector<png_bytep> rows(h);
  for (png_uint_32 y = 0; y < h; ++y) {
    rows[y] = img.pixels.data() + static_cast<std::size_t>(y) * w * 3;
  }
  if (!read_rows(p.png, rows.data())) {
    throw FormatError(path, "", std::string("unreadable PNG: ") + p.ctx.message);
  }
  return img;
}

}  // namespace sinew::postprocess
