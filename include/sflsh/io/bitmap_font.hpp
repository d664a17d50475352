#pragma once
// A tiny built-in 5x7 bitmap font for labels on rendered images (numbers,
// units, view names), so pictures explain themselves without a font library.
#include <string>

#include "sflsh/io/png_image.hpp"

namespace sflsh::io {

/// Glyph cell: 5 x 7 pixels plus one column / two rows of spacing, times `scale`.
inline constexpr int kGlyphWidth = 5, kGlyphHeight = 7, kGlyphAdvance = 6;

/// Width in pixels of `text` drawn at `scale`.
int text_width(const std::string& text, int scale = 1);
/// Height in pixels of one line at `scale`.
inline int text_height(int scale = 1) { return kGlyphHeight * scale; }

/// Draws `text` with its top-left corner at (x, y). Digits, A-Z (lower case
/// is drawn as upper case), space and . , - + : ( ) / = % _ are known;
/// anything else is drawn as '?'. Clipped at the image border.
void draw_text(Image& image, int x, int y, const std::string& text, Rgb8 color, int scale = 1);

}  // namespace sflsh::io
