#include "rebraid/io/gltf_material.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cstring>
#include <filesystem>

#include "rebraid/core/error.h"
#include "rebraid/io/gltf_accessor.h"
#include "rebraid/io/gltf_draco.h"

namespace rebraid {
namespace {

const tinygltf::Model& kept_model(const GltfLoadResult& loaded, const char* call) {
    if (!loaded.model)
        throw Error(std::string(call) + ": the glTF model was not kept (load with keep_model)");
    return *loaded.model;
}

GltfWrap wrap_mode(int gltf_wrap) {
    switch (gltf_wrap) {
        case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE:
            return GltfWrap::clamp_to_edge;
        case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT:
            return GltfWrap::mirrored_repeat;
        default:
            return GltfWrap::repeat;  // the glTF default, also for unknown values
    }
}

int hex_digit(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/// glTF URIs are percent-encoded (RFC 3986): "my%20image.png" names "my image.png".
std::string percent_decode(const std::string& uri) {
    std::string out;
    out.reserve(uri.size());
    for (std::size_t i = 0; i < uri.size(); ++i) {
        if (uri[i] == '%' && i + 2 < uri.size() && hex_digit(uri[i + 1]) >= 0 &&
            hex_digit(uri[i + 2]) >= 0) {
            out += static_cast<char>(hex_digit(uri[i + 1]) * 16 + hex_digit(uri[i + 2]));
            i += 2;
        } else {
            out += uri[i];
        }
    }
    return out;
}

/// Reads component `c` of element `e` as a float in [0, 1] for normalized integers.
float read_texcoord_component(const GltfElementRange& range, int component_type, std::uint64_t e,
                              int c) {
    const unsigned char* element = range.first + e * range.stride;
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT: {
            float value;
            std::memcpy(&value, element + 4 * c, 4);
            return value;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return static_cast<float>(element[c]) / 255.0f;
        default: {  // unsigned short, checked by the caller
            std::uint16_t value;
            std::memcpy(&value, element + 2 * c, 2);
            return static_cast<float>(value) / 65535.0f;
        }
    }
}

}  // namespace

std::vector<GltfMaterial> read_gltf_materials(const GltfLoadResult& loaded) {
    const tinygltf::Model& model = kept_model(loaded, "read_gltf_materials");
    std::vector<GltfMaterial> materials;
    materials.reserve(model.materials.size());
    for (std::size_t m = 0; m < model.materials.size(); ++m) {
        const tinygltf::Material& source = model.materials[m];
        const std::string label = "glTF material " + std::to_string(m) + " ('" + source.name + "')";
        GltfMaterial material;
        material.name = source.name;
        material.is_double_sided = source.doubleSided;
        const std::vector<double>& factor = source.pbrMetallicRoughness.baseColorFactor;
        if (factor.size() == 4)
            for (int c = 0; c < 4; ++c)
                material.base_colour_factor[c] = static_cast<float>(factor[c]);

        const tinygltf::TextureInfo& info = source.pbrMetallicRoughness.baseColorTexture;
        if (info.index >= 0) {
            if (static_cast<std::size_t>(info.index) >= model.textures.size())
                throw Error(label + " references texture " + std::to_string(info.index) +
                            ", file has " + std::to_string(model.textures.size()));
            const tinygltf::Texture& texture = model.textures[static_cast<std::size_t>(info.index)];
            // A texture without a source (e.g. only an extension's image) is left out.
            if (texture.source >= 0) {
                if (static_cast<std::size_t>(texture.source) >= model.images.size())
                    throw Error(label + ": texture " + std::to_string(info.index) +
                                " references image " + std::to_string(texture.source) +
                                ", file has " + std::to_string(model.images.size()));
                GltfBaseColourTexture base;
                base.image_id = static_cast<std::uint32_t>(texture.source);
                base.texcoord_set = static_cast<std::uint32_t>(std::max(0, info.texCoord));
                if (texture.sampler >= 0 &&
                    static_cast<std::size_t>(texture.sampler) < model.samplers.size()) {
                    const tinygltf::Sampler& sampler =
                        model.samplers[static_cast<std::size_t>(texture.sampler)];
                    base.sampler.wrap_s = wrap_mode(sampler.wrapS);
                    base.sampler.wrap_t = wrap_mode(sampler.wrapT);
                    base.sampler.is_nearest = sampler.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST;
                }
                material.base_colour_texture = base;
            }
        }
        materials.push_back(std::move(material));
    }
    return materials;
}

std::vector<GltfImageSource> read_gltf_image_sources(const GltfLoadResult& loaded,
                                                     const std::string& gltf_path) {
    const tinygltf::Model& model = kept_model(loaded, "read_gltf_image_sources");
    const std::filesystem::path folder = std::filesystem::path(gltf_path).parent_path();
    std::vector<GltfImageSource> sources;
    sources.reserve(model.images.size());
    for (std::size_t i = 0; i < model.images.size(); ++i) {
        const tinygltf::Image& image = model.images[i];
        GltfImageSource source;
        source.name = image.name;
        source.mime_type = image.mimeType;
        if (image.bufferView >= 0) {
            const std::string label = "scene file '" + gltf_path + "': image " + std::to_string(i) +
                                      " ('" + image.name + "')";
            if (static_cast<std::size_t>(image.bufferView) >= model.bufferViews.size())
                throw Error(label + " references bufferView " + std::to_string(image.bufferView) +
                            ", file has " + std::to_string(model.bufferViews.size()));
            const tinygltf::BufferView& view =
                model.bufferViews[static_cast<std::size_t>(image.bufferView)];
            if (view.buffer < 0 || static_cast<std::size_t>(view.buffer) >= model.buffers.size())
                throw Error(label + ": bufferView " + std::to_string(image.bufferView) +
                            " references buffer " + std::to_string(view.buffer) + ", file has " +
                            std::to_string(model.buffers.size()));
            const std::vector<unsigned char>& buffer =
                model.buffers[static_cast<std::size_t>(view.buffer)].data;
            if (!gltf_elements_fit(view.byteOffset, 1, 1, view.byteLength, buffer.size()))
                throw Error(label + ": bufferView " + std::to_string(image.bufferView) +
                            " (byteOffset " + std::to_string(view.byteOffset) + ", byteLength " +
                            std::to_string(view.byteLength) + ") runs past its buffer (" +
                            std::to_string(buffer.size()) + " bytes)");
            const auto first = buffer.begin() + static_cast<std::ptrdiff_t>(view.byteOffset);
            source.encoded_bytes.assign(first,
                                        first + static_cast<std::ptrdiff_t>(view.byteLength));
        } else if (!image.uri.empty() && image.uri.rfind("data:", 0) != 0) {
            source.file_path = (folder / percent_decode(image.uri)).string();
        }
        sources.push_back(std::move(source));
    }
    return sources;
}

std::vector<std::vector<std::array<float, 2>>> read_gltf_base_colour_uvs(
    const GltfLoadResult& loaded, const std::vector<GltfMaterial>& materials) {
    const tinygltf::Model& model = kept_model(loaded, "read_gltf_base_colour_uvs");
    std::vector<std::vector<std::array<float, 2>>> uvs(loaded.scene.meshes.size());
    for (std::size_t m = 0; m < uvs.size() && m < loaded.report.mesh_primitives.size(); ++m) {
        for (const GltfPrimitiveRange& range : loaded.report.mesh_primitives[m]) {
            if (range.material < 0 || static_cast<std::size_t>(range.material) >= materials.size())
                continue;
            const auto& texture =
                materials[static_cast<std::size_t>(range.material)].base_colour_texture;
            if (!texture) continue;
            const tinygltf::Primitive& primitive = model.meshes[m].primitives[range.gltf_primitive];
            const std::string attribute = "TEXCOORD_" + std::to_string(texture->texcoord_set);
            const auto found = primitive.attributes.find(attribute);
            // A texture without its coordinates is sampled at (0, 0), as other viewers do.
            if (found == primitive.attributes.end()) continue;

            const std::string role = attribute + " of mesh " + std::to_string(m) + " primitive " +
                                     std::to_string(range.gltf_primitive);
            const std::string prefix = "glTF base colour texture coordinates: ";
            if (uses_gltf_draco(primitive)) {
                std::vector<std::array<float, 2>> decoded =
                    decode_gltf_draco_texcoords(model, primitive, attribute,
                                                "mesh " + std::to_string(m) + " primitive " +
                                                    std::to_string(range.gltf_primitive),
                                                prefix);
                if (!decoded.empty()) {
                    // One per decoded point, as many as the primitive's positions (the Draco
                    // decoder checks both against the POSITION accessor's count).
                    if (uvs[m].empty())
                        uvs[m].assign(loaded.scene.meshes[m].positions.size(), {0, 0});
                    std::copy(decoded.begin(), decoded.end(),
                              uvs[m].begin() + std::ptrdiff_t(range.first_vertex));
                    continue;
                }
            }
            const GltfElementRange elements =
                resolve_gltf_accessor(model, found->second, role, prefix);
            const tinygltf::Accessor& accessor =
                model.accessors[static_cast<std::size_t>(found->second)];
            const int type = accessor.componentType;
            if (accessor.type != TINYGLTF_TYPE_VEC2 ||
                (type != TINYGLTF_COMPONENT_TYPE_FLOAT &&
                 type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                 type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT))
                throw Error(prefix + role + " is not VEC2 of float, unsigned byte or short");
            if (elements.count != range.vertex_count)
                throw Error(prefix + role + " has " + std::to_string(elements.count) +
                            " elements, the primitive has " + std::to_string(range.vertex_count) +
                            " positions");
            if (uvs[m].empty()) uvs[m].assign(loaded.scene.meshes[m].positions.size(), {0, 0});
            for (std::uint64_t e = 0; e < elements.count; ++e)
                uvs[m][range.first_vertex + e] = {read_texcoord_component(elements, type, e, 0),
                                                  read_texcoord_component(elements, type, e, 1)};
        }
    }
    return uvs;
}

}  // namespace rebraid
