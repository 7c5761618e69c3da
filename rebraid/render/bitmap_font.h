#pragma once

#include <array>
#include <string_view>

namespace rebraid::viewer {

/// Glyphs of the built-in 5 x 7 pixel font: digits, upper-case letters and common
/// punctuation. Lower-case letters are drawn as upper case.
inline constexpr int kGlyphWidth = 5;
inline constexpr int kGlyphHeight = 7;
/// Horizontal and vertical distance between neighbouring characters, at scale 1.
inline constexpr int kGlyphAdvance = kGlyphWidth + 1;
inline constexpr int kLineAdvance = kGlyphHeight + 3;

/// One glyph: row r (top first) is `rows[r]`, bit 4 the leftmost pixel.
struct Glyph {
    std::array<unsigned char, kGlyphHeight> rows{};
};

/// The glyph of `c`; a hollow box for characters the font lacks. Space is empty.
const Glyph& glyph_for(char c);

/// Width in pixels of `text` drawn at `scale` (no trailing gap).
int text_width(std::string_view text, int scale);

}  // namespace rebraid::viewer
