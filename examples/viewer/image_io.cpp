#include "viewer/image_io.h"

#include <OpenImageIO/imageio.h>

#include "rebraid/error.h"

namespace rebraid::viewer {

void check_image_format(const std::string& path) {
    if (!OIIO::ImageOutput::create(path))
        throw Error("check_image_format: no image writer for '" + path + "': " + OIIO::geterror());
}

void write_image(const std::string& path, const Image& image) {
    auto out = OIIO::ImageOutput::create(path);
    if (!out) throw Error("write_image: cannot write '" + path + "': " + OIIO::geterror());
    // 8-bit channels for PNG and friends; OpenImageIO converts from float and clamps.
    OIIO::ImageSpec spec(image.width, image.height, 3, OIIO::TypeDesc::UINT8);
    if (path.ends_with(".exr")) spec.set_format(OIIO::TypeDesc::HALF);
    if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, image.rgb.data()) ||
        !out->close())
        throw Error("write_image: cannot write '" + path + "': " + out->geterror());
}

}  // namespace rebraid::viewer
