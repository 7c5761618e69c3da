#include "rebraid/render/texture.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "rebraid/core/error.h"
#include "rebraid/render/colour.h"

namespace rebraid::viewer {

namespace {

/// Textures larger than this are a memory risk, not a picture.
constexpr long long kMaxTexels = 1ll << 26;

/// A texel index for coordinate index `i` of a `size`-texel axis under `wrap`.
int wrap_index(int i, int size, GltfWrap wrap) {
    switch (wrap) {
        case GltfWrap::clamp_to_edge:
            return std::clamp(i, 0, size - 1);
        case GltfWrap::mirrored_repeat: {
            const int period = 2 * size;
            int m = i % period;
            if (m < 0) m += period;
            return m < size ? m : period - 1 - m;
        }
        case GltfWrap::repeat:
        default: {
            int m = i % size;
            return m < 0 ? m + size : m;
        }
    }
}

/// File name OpenImageIO uses to pick a reader for embedded bytes.
std::string format_hint(const GltfImageSource& source) {
    if (source.mime_type == "image/jpeg") return "embedded.jpg";
    if (source.mime_type == "image/png") return "embedded.png";
    // No MIME type: sniff the signature.
    const auto& b = source.encoded_bytes;
    if (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return "embedded.jpg";
    return "embedded.png";
}

}  // namespace

Texture::Texture(int width, int height, std::vector<float> linear_rgb)
    : width_(width), height_(height), linear_rgb_(std::move(linear_rgb)) {
    if (width_ < 1 || height_ < 1 ||
        linear_rgb_.size() != 3 * static_cast<std::size_t>(width_) * height_)
        throw Error("Texture: " + std::to_string(width_) + " x " + std::to_string(height_) +
                    " texels do not match " + std::to_string(linear_rgb_.size()) + " values");
}

Texture Texture::decode(const GltfImageSource& source, const std::string& source_label) {
    if (!source.is_available())
        throw Error("Texture::decode: " + source_label +
                    " has no file or bufferView (data: URIs are not supported)");
    std::unique_ptr<OIIO::Filesystem::IOMemReader> memory;
    std::unique_ptr<OIIO::ImageInput> input;
    if (!source.encoded_bytes.empty()) {
        memory = std::make_unique<OIIO::Filesystem::IOMemReader>(source.encoded_bytes.data(),
                                                                 source.encoded_bytes.size());
        input = OIIO::ImageInput::open(format_hint(source), nullptr, memory.get());
    } else {
        input = OIIO::ImageInput::open(source.file_path);
    }
    const std::string where =
        source.file_path.empty() ? source_label : source_label + " ('" + source.file_path + "')";
    if (!input) throw Error("Texture::decode: cannot read " + where + ": " + OIIO::geterror());

    const OIIO::ImageSpec& spec = input->spec();
    const int width = spec.width, height = spec.height, channels = spec.nchannels;
    if (width < 1 || height < 1 || channels < 1 ||
        static_cast<long long>(width) * height > kMaxTexels)
        throw Error("Texture::decode: " + where + " has unsupported size " + std::to_string(width) +
                    " x " + std::to_string(height) + " x " + std::to_string(channels));
    std::vector<float> values(static_cast<std::size_t>(width) * height * channels);
    if (!input->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, values.data()))
        throw Error("Texture::decode: cannot decode " + where + ": " + input->geterror());
    input->close();

    std::vector<float> rgb(3 * static_cast<std::size_t>(width) * height);
    for (std::size_t texel = 0; texel < static_cast<std::size_t>(width) * height; ++texel) {
        const float* in = &values[texel * channels];
        const bool is_grey = channels < 3;
        for (int c = 0; c < 3; ++c) rgb[3 * texel + c] = srgb_to_linear(is_grey ? in[0] : in[c]);
    }
    return Texture(width, height, std::move(rgb));
}

Vec3f Texture::texel(int x, int y) const {
    const std::size_t at = 3 * (static_cast<std::size_t>(y) * width_ + x);
    return {linear_rgb_[at], linear_rgb_[at + 1], linear_rgb_[at + 2]};
}

Vec3f Texture::sample(float u, float v, const GltfSampler& sampler) const {
    if (!std::isfinite(u) || !std::isfinite(v)) return texel(0, 0);
    // Texel centres at half-integer positions.
    const float x = u * static_cast<float>(width_) - 0.5f;
    const float y = v * static_cast<float>(height_) - 0.5f;
    // Keep floor() in int range for wild coordinates; repeat wraps them anyway.
    const float fx = std::floor(std::clamp(x, -1e7f, 1e7f));
    const float fy = std::floor(std::clamp(y, -1e7f, 1e7f));
    const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
    if (sampler.is_nearest) {
        const int nx = static_cast<int>(std::floor(std::clamp(x + 0.5f, -1e7f, 1e7f)));
        const int ny = static_cast<int>(std::floor(std::clamp(y + 0.5f, -1e7f, 1e7f)));
        return texel(wrap_index(nx, width_, sampler.wrap_s),
                     wrap_index(ny, height_, sampler.wrap_t));
    }
    const float wx = std::clamp(x - fx, 0.0f, 1.0f), wy = std::clamp(y - fy, 0.0f, 1.0f);
    const int xa = wrap_index(x0, width_, sampler.wrap_s);
    const int xb = wrap_index(x0 + 1, width_, sampler.wrap_s);
    const int ya = wrap_index(y0, height_, sampler.wrap_t);
    const int yb = wrap_index(y0 + 1, height_, sampler.wrap_t);
    const Vec3f top = texel(xa, ya) * (1.0f - wx) + texel(xb, ya) * wx;
    const Vec3f bottom = texel(xa, yb) * (1.0f - wx) + texel(xb, yb) * wx;
    return top * (1.0f - wy) + bottom * wy;
}

}  // namespace rebraid::viewer
