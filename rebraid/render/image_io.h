#pragma once

#include <string>
#include <vector>

#include "rebraid/core/types.h"

namespace rebraid::viewer {

/// An RGB image of linear-light floats (>= 0, 1 = white), row-major, top row first.
struct Image {
    int width = 0;
    int height = 0;
    std::vector<float> rgb;  ///< 3 * width * height

    /// A `width` x `height` image filled with `colour` (linear).
    static Image filled(int width, int height, Vec3f colour = {});

    Vec3f pixel(int x, int y) const;
    void set_pixel(int x, int y, Vec3f colour);
};

/// Writes through OpenImageIO; the format follows the file name. EXR files get the linear
/// values as half floats; every other format gets 8-bit sRGB-encoded values, clamped to
/// [0, 1]. Throws rebraid::Error naming the file when OpenImageIO fails.
void write_image(const std::string& path, const Image& image);

/// Throws rebraid::Error naming the file when OpenImageIO has no writer for its extension.
/// Cheap (creates no file); lets a command fail before rendering.
void check_image_format(const std::string& path);

}  // namespace rebraid::viewer
