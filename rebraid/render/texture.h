#pragma once

#include <string>
#include <vector>

#include "rebraid/core/types.h"
#include "rebraid/io/gltf_material.h"

namespace rebraid::viewer {

/// A decoded colour texture: linear RGB texels, row-major, top row first (glTF puts
/// texture coordinate (0, 0) at the image's top-left corner).
class Texture {
public:
    /// Decodes the image through OpenImageIO, from its file or its embedded bytes, and turns
    /// its sRGB values into linear ones (base colour textures are sRGB-encoded). Grey and
    /// grey-alpha images become grey RGB; alpha is dropped. Throws rebraid::Error naming
    /// `source_label` when the image is unavailable or cannot be decoded.
    static Texture decode(const GltfImageSource& source, const std::string& source_label);

    /// A texture of `width` x `height` linear texels (3 floats each, row-major).
    Texture(int width, int height, std::vector<float> linear_rgb);

    /// The colour at texture coordinates (u, v) with the sampler's wrap modes, filtered
    /// bilinearly (or nearest, when the sampler says so).
    Vec3f sample(float u, float v, const GltfSampler& sampler) const;

    int width() const { return width_; }
    int height() const { return height_; }

private:
    Vec3f texel(int x, int y) const;

    int width_ = 0;
    int height_ = 0;
    std::vector<float> linear_rgb_;
};

}  // namespace rebraid::viewer
