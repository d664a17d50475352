#pragma once
// An 8-bit RGB image in memory and its PNG file (libpng).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace sflsh::io {

/// 8-bit sRGB colour.
using Rgb8 = std::array<std::uint8_t, 3>;

/// Row-major RGB8 image; pixel (x, y) with y = 0 at the top.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  ///< width * height * 3 bytes

  Image() = default;
  Image(int w, int h, Rgb8 fill = {0, 0, 0});
  std::uint8_t* at(int x, int y) { return rgb.data() + (size_t(y) * size_t(width) + size_t(x)) * 3; }
  const std::uint8_t* at(int x, int y) const { return rgb.data() + (size_t(y) * size_t(width) + size_t(x)) * 3; }
  Rgb8 pixel(int x, int y) const { return {at(x, y)[0], at(x, y)[1], at(x, y)[2]}; }
  /// Sets a pixel; coordinates outside the image are ignored.
  void set(int x, int y, Rgb8 c);
  /// Fills the rectangle [x0, x1) x [y0, y1) (clipped).
  void fill_rect(int x0, int y0, int x1, int y1, Rgb8 c);
  /// Copies `src` with its top-left corner at (x, y) (clipped).
  void blit(const Image& src, int x, int y);
};

/// Writes an RGB8 PNG atomically. Throws naming the path on failure.
void write_png(const std::string& path, const Image& image);
/// Reads a PNG (any bit depth / colour type is converted to RGB8).
Image read_png(const std::string& path);

}  // namespace sflsh::io
