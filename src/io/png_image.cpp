#include "sflsh/io/png_image.hpp"

#include <algorithm>
#include <cstdio>
#include <memory>

#include <png.h>

#include "sflsh/core/error.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh::io {

Image::Image(int w, int h, Rgb8 fill) : width(w), height(h), rgb(size_t(w) * size_t(h) * 3) {
  require(w >= 0 && h >= 0, "image size must be non-negative, got ", w, " x ", h);
  for (size_t i = 0; i < rgb.size(); i += 3) std::copy(fill.begin(), fill.end(), rgb.begin() + long(i));
}

void Image::set(int x, int y, Rgb8 c) {
  if (x < 0 || y < 0 || x >= width || y >= height) return;
  std::copy(c.begin(), c.end(), at(x, y));
}

void Image::fill_rect(int x0, int y0, int x1, int y1, Rgb8 c) {
  x0 = std::max(x0, 0), y0 = std::max(y0, 0), x1 = std::min(x1, width), y1 = std::min(y1, height);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) std::copy(c.begin(), c.end(), at(x, y));
}

void Image::blit(const Image& src, int x, int y) {
  for (int sy = 0; sy < src.height; ++sy) {
    const int ty = y + sy;
    if (ty < 0 || ty >= height) continue;
    const int sx0 = std::max(0, -x), sx1 = std::min(src.width, width - x);
    if (sx1 <= sx0) continue;
    std::copy(src.at(sx0, sy), src.at(sx0, sy) + size_t(sx1 - sx0) * 3, at(x + sx0, ty));
  }
}

namespace {

struct FileCloser {
  void operator()(FILE* f) const {
    if (f) std::fclose(f);
  }
};

/// libpng reports errors through a callback that must not return. Throwing a
/// C++ exception through libpng's C frames is undefined, so the callback
/// records the message and long-jumps back to the setjmp point in our code.
struct PngError {
  char message[256] = "";
};

void on_png_error(png_structp png, png_const_charp msg) {
  auto* err = static_cast<PngError*>(png_get_error_ptr(png));
  std::snprintf(err->message, sizeof err->message, "%s", msg);
  png_longjmp(png, 1);
}
void on_png_warning(png_structp, png_const_charp) {}

}  // namespace

void write_png(const std::string& path, const Image& image) {
  require(image.width > 0 && image.height > 0, path, ": cannot write an empty image (", image.width, " x ",
          image.height, ")");
  require(image.rgb.size() == size_t(image.width) * size_t(image.height) * 3, path,
          ": image buffer has the wrong size");
  AtomicOutput out(path);
  std::unique_ptr<FILE, FileCloser> file(std::fopen(out.temp_path().c_str(), "wb"));
  require(file != nullptr, path, ": cannot open ", out.temp_path(), " for writing");

  PngError err;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &err, on_png_error, on_png_warning);
  require(png != nullptr, path, ": libpng could not start");
  png_infop info = png_create_info_struct(png);
  volatile bool ok = false;
  if (info && !setjmp(png_jmpbuf(png))) {
    png_init_io(png, file.get());
    png_set_IHDR(png, info, png_uint_32(image.width), png_uint_32(image.height), 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_compression_level(png, 6);
    png_write_info(png, info);
    for (int y = 0; y < image.height; ++y) png_write_row(png, image.at(0, y));
    png_write_end(png, nullptr);
    ok = true;
  }
  png_destroy_write_struct(&png, &info);
  require(ok, path, ": PNG encoding failed: ", err.message);
  require(std::fflush(file.get()) == 0 && !std::ferror(file.get()), path, ": write failed (disk full?)");
  file.reset();
  out.commit();
}

Image read_png(const std::string& path) {
  std::unique_ptr<FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  require(file != nullptr, path, ": cannot open for reading");
  unsigned char sig[8];
  require(std::fread(sig, 1, 8, file.get()) == 8 && png_sig_cmp(sig, 0, 8) == 0, path, ": not a PNG file");

  PngError err;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &err, on_png_error, on_png_warning);
  require(png != nullptr, path, ": libpng could not start");
  png_infop info = png_create_info_struct(png);
  Image image;
  volatile bool ok = false;
  if (info && !setjmp(png_jmpbuf(png))) {
    png_init_io(png, file.get());
    png_set_sig_bytes(png, 8);
    png_read_info(png, info);
    // Normalize every colour type / bit depth to 8-bit RGB.
    png_set_expand(png);
    png_set_strip_16(png);
    png_set_strip_alpha(png);
    png_set_gray_to_rgb(png);
    png_read_update_info(png, info);
    const int w = int(png_get_image_width(png, info)), h = int(png_get_image_height(png, info));
    image = Image(w, h);
    std::vector<png_bytep> rows(static_cast<size_t>(h));
    for (int y = 0; y < h; ++y) rows[size_t(y)] = image.at(0, y);
    png_read_image(png, rows.data());
    png_read_end(png, nullptr);
    ok = true;
  }
  png_destroy_read_struct(&png, &info, nullptr);
  require(ok, path, ": PNG decoding failed: ", err.message);
  return image;
}

}  // namespace sflsh::io
