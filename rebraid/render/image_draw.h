#pragma once

#include <string_view>

#include "rebraid/core/types.h"
#include "rebraid/render/image_io.h"

namespace rebraid::viewer {

/// An axis-aligned pixel rectangle: columns [x, x + width), rows [y, y + height).
struct PixelRect {
    int x = 0;
    int y = 0;
    int width = 0;
    int height = 0;
};

/// Blends `colour` (display values) over the pixels of `rect` inside `image` with the given
/// opacity in [0, 1]; parts outside the image are skipped.
void fill_rect(Image& image, const PixelRect& rect, Vec3f colour, float opacity = 1.0f);

/// Draws `text` with the built-in font, top-left corner at (`x`, `y`), each font pixel
/// `scale` x `scale` image pixels, in `colour` (display values). Clipped to the image.
void draw_text(Image& image, int x, int y, std::string_view text, int scale, Vec3f colour);

/// draw_text() on a dark translucent box with a margin, so the text reads on any picture.
/// Returns the box drawn.
PixelRect draw_label(Image& image, int x, int y, std::string_view text, int scale);

/// Copies `source` into `target` with its top-left corner at (`x`, `y`), clipped.
void paste_image(Image& target, const Image& source, int x, int y);

}  // namespace rebraid::viewer
