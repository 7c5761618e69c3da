#include "rebraid/render/image_io.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cctype>

#include "rebraid/core/error.h"
#include "rebraid/render/colour.h"

namespace rebraid::viewer {

namespace {

bool is_exr_path(const std::string& path) {
    std::string lower = path;
    std::ranges::transform(lower, lower.begin(),
                           [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return lower.ends_with(".exr");
}

}  // namespace

Image Image::filled(int width, int height, Vec3f colour) {
    Image image;
    image.width = width;
    image.height = height;
    image.rgb.resize(3 * static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
    for (std::size_t i = 0; i < image.rgb.size(); i += 3) {
        image.rgb[i] = colour.x;
        image.rgb[i + 1] = colour.y;
        image.rgb[i + 2] = colour.z;
    }
    return image;
}

Vec3f Image::pixel(int x, int y) const {
    const std::size_t at = 3 * (static_cast<std::size_t>(y) * width + x);
    return {rgb[at], rgb[at + 1], rgb[at + 2]};
}

void Image::set_pixel(int x, int y, Vec3f colour) {
    const std::size_t at = 3 * (static_cast<std::size_t>(y) * width + x);
    rgb[at] = colour.x;
    rgb[at + 1] = colour.y;
    rgb[at + 2] = colour.z;
}

void check_image_format(const std::string& path) {
    if (!OIIO::ImageOutput::create(path)) {
        OIIO::geterror();  // clears OpenImageIO's longer message, which says the same
        throw Error("no image writer for '" + path +
                    "': name the image .png, or .exr for linear half-float");
    }
}

void write_image(const std::string& path, const Image& image) {
    auto out = OIIO::ImageOutput::create(path);
    if (!out) throw Error("cannot write image '" + path + "': " + OIIO::geterror());
    const bool is_linear_format = is_exr_path(path);
    OIIO::ImageSpec spec(image.width, image.height, 3,
                         is_linear_format ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::UINT8);
    std::vector<float> values = image.rgb;
    if (!is_linear_format) {
        // Encode ourselves: OpenImageIO would store linear values as they are. It rounds and
        // clamps on the conversion to 8 bits.
        for (float& value : values) value = linear_to_srgb(value);
    }
    if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, values.data()) ||
        !out->close())
        throw Error("cannot write image '" + path + "': " + out->geterror());
}

}  // namespace rebraid::viewer
