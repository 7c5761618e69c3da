#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "rebraid/io/gltf_scene.h"

namespace rebraid {

/// How texture coordinates outside [0, 1] are folded back (glTF sampler wrapS / wrapT).
enum class GltfWrap { repeat, clamp_to_edge, mirrored_repeat };

/// A glTF sampler, reduced to what a simple renderer uses.
struct GltfSampler {
    GltfWrap wrap_s = GltfWrap::repeat;
    GltfWrap wrap_t = GltfWrap::repeat;
    bool is_nearest = false;  ///< magFilter NEAREST (otherwise bilinear)
};

/// The base colour texture of a material: image, texture-coordinate set and sampler.
struct GltfBaseColourTexture {
    std::uint32_t image_id = 0;      ///< index in the glTF `images` array
    std::uint32_t texcoord_set = 0;  ///< n of TEXCOORD_n
    GltfSampler sampler;
};

/// The parts of a glTF metallic-roughness material that diffuse shading uses.
struct GltfMaterial {
    std::string name;
    /// Linear RGBA multiplier of the base colour (glTF default: opaque white).
    std::array<float, 4> base_colour_factor{1.0f, 1.0f, 1.0f, 1.0f};
    /// Sampled and multiplied by the factor; colours in it are sRGB-encoded (glTF spec).
    std::optional<GltfBaseColourTexture> base_colour_texture;
    bool is_double_sided = false;
};

/// Where a glTF image's encoded bytes (PNG, JPEG, ...) are. Decoding is the caller's job.
struct GltfImageSource {
    std::string name;
    /// The image file next to the glTF file (its `uri`, percent-decoded), or empty.
    std::string file_path;
    /// Bytes of the image's bufferView (images embedded in a .glb or a buffer), or empty.
    std::vector<unsigned char> encoded_bytes;
    /// `mimeType` as given ("image/png", "image/jpeg"), possibly empty.
    std::string mime_type;
    /// False for images this reader cannot reach (base64 `data:` URIs, which the loader
    /// drops without decoding).
    bool is_available() const { return !file_path.empty() || !encoded_bytes.empty(); }
};

/// Every material of the document, in glTF order (a primitive's `material` indexes it).
/// `loaded` must hold the model (GltfLoadOptions::keep_model). Throws rebraid::Error naming
/// the material for a missing model or a texture reference to a missing texture or image.
std::vector<GltfMaterial> read_gltf_materials(const GltfLoadResult& loaded);

/// Every image of the document, in glTF order. `gltf_path` is the loaded file, against whose
/// folder `uri`s are resolved. Throws rebraid::Error naming the image for a missing model or a
/// bufferView outside its buffer.
std::vector<GltfImageSource> read_gltf_image_sources(const GltfLoadResult& loaded,
                                                     const std::string& gltf_path);

/// Texture coordinates for the base colour texture of every Mesh vertex, per MeshId: each
/// loaded primitive whose material has a base colour texture contributes the TEXCOORD_n set
/// that texture names, in vertex order (GltfPrimitiveRange); vertices of other primitives, and
/// of primitives lacking that attribute, get (0, 0). A mesh with no coordinates at all gets an
/// empty list. Float and normalized unsigned byte/short coordinates are read, and those a
/// KHR_draco_mesh_compression primitive compresses are decoded with its mesh. Throws
/// rebraid::Error naming the mesh and primitive for an attribute of another type, a count
/// that differs from the primitive's positions, or an accessor outside its buffer.
std::vector<std::vector<std::array<float, 2>>> read_gltf_base_colour_uvs(
    const GltfLoadResult& loaded, const std::vector<GltfMaterial>& materials);

}  // namespace rebraid
