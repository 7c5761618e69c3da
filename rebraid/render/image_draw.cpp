#include "rebraid/render/image_draw.h"

#include <algorithm>

#include "rebraid/render/bitmap_font.h"
#include "rebraid/render/colour.h"

namespace rebraid::viewer {

void fill_rect(Image& image, const PixelRect& rect, Vec3f colour, float opacity) {
    const Vec3f linear = srgb_to_linear(colour);
    const float alpha = std::clamp(opacity, 0.0f, 1.0f);
    const int x_end = std::min(image.width, rect.x + rect.width);
    const int y_end = std::min(image.height, rect.y + rect.height);
    for (int y = std::max(0, rect.y); y < y_end; ++y)
        for (int x = std::max(0, rect.x); x < x_end; ++x)
            image.set_pixel(x, y, image.pixel(x, y) * (1.0f - alpha) + linear * alpha);
}

void draw_text(Image& image, int x, int y, std::string_view text, int scale, Vec3f colour) {
    const int s = std::max(1, scale);
    int pen_x = x;
    for (char c : text) {
        const Glyph& glyph = glyph_for(c);
        for (int row = 0; row < kGlyphHeight; ++row)
            for (int column = 0; column < kGlyphWidth; ++column)
                if (glyph.rows[row] & (1u << (kGlyphWidth - 1 - column)))
                    fill_rect(image, {pen_x + column * s, y + row * s, s, s}, colour);
        pen_x += kGlyphAdvance * s;
    }
}

PixelRect draw_label(Image& image, int x, int y, std::string_view text, int scale) {
    const int s = std::max(1, scale);
    const int margin = 2 * s;
    const PixelRect box{x, y, text_width(text, s) + 2 * margin, kGlyphHeight * s + 2 * margin};
    fill_rect(image, box, {0.0f, 0.0f, 0.0f}, 0.6f);
    draw_text(image, x + margin, y + margin, text, s, {1.0f, 1.0f, 1.0f});
    return box;
}

void paste_image(Image& target, const Image& source, int x, int y) {
    for (int sy = 0; sy < source.height; ++sy) {
        const int ty = y + sy;
        if (ty < 0 || ty >= target.height) continue;
        for (int sx = 0; sx < source.width; ++sx) {
            const int tx = x + sx;
            if (tx >= 0 && tx < target.width) target.set_pixel(tx, ty, source.pixel(sx, sy));
        }
    }
}

}  // namespace rebraid::viewer
