#pragma once

#include <string>
#include <vector>

namespace rebraid::viewer {

/// An RGB image of floats in [0,1], row-major, top row first.
struct Image {
    int width = 0;
    int height = 0;
    std::vector<float> rgb;  ///< 3 * width * height
};

/// Writes through OpenImageIO; the format follows the file name (PNG, EXR, ...).
/// Throws rebraid::Error naming the file when OpenImageIO fails.
void write_image(const std::string& path, const Image& image);

/// Throws rebraid::Error naming the file when OpenImageIO has no writer for its extension.
/// Cheap (creates no file); lets a command fail before rendering.
void check_image_format(const std::string& path);

}  // namespace rebraid::viewer
