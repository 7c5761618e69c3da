#include "rebraid/io/gltf_draco.h"

#include <draco/compression/decode.h>
#include <tiny_gltf.h>

#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <utility>

#include "rebraid/core/error.h"
#include "rebraid/io/gltf_accessor.h"

namespace rebraid {

bool uses_gltf_draco(const tinygltf::Primitive& primitive) {
    return primitive.extensions.count(kGltfDracoCompression) != 0;
}

namespace {

/// The checked extension of `primitive` and its decoded mesh: what both decoders share.
struct DecodedDraco {
    std::unique_ptr<draco::Mesh> mesh;
    std::uint64_t vertex_count = 0;
    std::uint64_t index_count = 0;
    const tinygltf::Value* attributes = nullptr;  ///< the extension's attributes object
};

DecodedDraco decode_draco_mesh(const tinygltf::Model& model, const tinygltf::Primitive& primitive,
                               const std::string& label, const std::string& error_prefix,
                               std::uint64_t max_vertices, std::uint64_t max_triangles) {
    auto fail = [&](const std::string& what) { throw Error(error_prefix + label + ": " + what); };
    const tinygltf::Value& extension = primitive.extensions.at(kGltfDracoCompression);
    if (!extension.IsObject() || !extension.Has("bufferView") ||
        !extension.Get("bufferView").IsInt() || !extension.Has("attributes") ||
        !extension.Get("attributes").IsObject())
        fail("needs a bufferView index and an attributes object");
    const int mode = primitive.mode < 0 ? TINYGLTF_MODE_TRIANGLES : primitive.mode;
    if (mode != TINYGLTF_MODE_TRIANGLES) fail("only mode TRIANGLES is supported");

    // The accessors describe the decoded data: their counts bound what may be decoded.
    const auto position = primitive.attributes.find("POSITION");
    if (position == primitive.attributes.end()) fail("the primitive has no POSITION attribute");
    auto accessor_count = [&](int id, const char* role) {
        if (id < 0 || std::size_t(id) >= model.accessors.size())
            fail(std::string(role) + " references accessor " + std::to_string(id) + ", file has " +
                 std::to_string(model.accessors.size()) + " accessors");
        return std::uint64_t(model.accessors[std::size_t(id)].count);
    };
    DecodedDraco decoded;
    decoded.attributes = &extension.Get("attributes");
    decoded.vertex_count = accessor_count(position->second, "POSITION");
    if (primitive.indices < 0) fail("the primitive has no indices accessor");
    decoded.index_count = accessor_count(primitive.indices, "indices");
    if (decoded.vertex_count > max_vertices || decoded.index_count / 3 > max_triangles)
        fail("declares " + std::to_string(decoded.vertex_count) + " vertices and " +
             std::to_string(decoded.index_count / 3) + " triangles, more than max_vertices = " +
             std::to_string(max_vertices) + " or max_triangles = " + std::to_string(max_triangles));

    const int view_id = extension.Get("bufferView").GetNumberAsInt();
    if (view_id < 0 || std::size_t(view_id) >= model.bufferViews.size())
        fail("references bufferView " + std::to_string(view_id) + ", file has " +
             std::to_string(model.bufferViews.size()));
    const tinygltf::BufferView& view = model.bufferViews[std::size_t(view_id)];
    if (view.buffer < 0 || std::size_t(view.buffer) >= model.buffers.size())
        fail("bufferView " + std::to_string(view_id) + " references a missing buffer");
    const std::vector<unsigned char>& buffer = model.buffers[std::size_t(view.buffer)].data;
    if (!gltf_elements_fit(view.byteOffset, 1, 1, view.byteLength, buffer.size()))
        fail("bufferView " + std::to_string(view_id) + " runs past the end of its buffer");

    draco::DecoderBuffer compressed;
    compressed.Init(reinterpret_cast<const char*>(buffer.data() + view.byteOffset),
                    view.byteLength);
    draco::Decoder decoder;
    auto result = decoder.DecodeMeshFromBuffer(&compressed);
    if (!result.ok()) fail("corrupt Draco data (" + result.status().error_msg_string() + ")");
    decoded.mesh = std::move(result).value();
    if (decoded.mesh->num_points() != decoded.vertex_count ||
        std::uint64_t(decoded.mesh->num_faces()) * 3 != decoded.index_count)
        fail("decoded " + std::to_string(decoded.mesh->num_points()) + " points and " +
             std::to_string(decoded.mesh->num_faces()) + " triangles, the accessors say " +
             std::to_string(decoded.vertex_count) + " and " +
             std::to_string(decoded.index_count / 3));
    return decoded;
}

/// The decoded attribute the extension names `name` (e.g. "POSITION"), of at least
/// `components` components; null when the extension does not name it.
const draco::PointAttribute* named_attribute(const DecodedDraco& decoded, const std::string& name,
                                             int components, const std::string& label,
                                             const std::string& error_prefix) {
    auto fail = [&](const std::string& what) { throw Error(error_prefix + label + ": " + what); };
    if (!decoded.attributes->Has(name)) return nullptr;
    const tinygltf::Value& id = decoded.attributes->Get(name);
    if (!id.IsInt() || id.GetNumberAsInt() < 0) fail("needs the Draco attribute id of " + name);
    const draco::PointAttribute* attribute =
        decoded.mesh->GetAttributeByUniqueId(std::uint32_t(id.GetNumberAsInt()));
    if (!attribute)
        fail("the decoded mesh has no attribute " + std::to_string(id.GetNumberAsInt()) + " (" +
             name + ")");
    if (attribute->num_components() < components)
        fail("the decoded " + name + " has " + std::to_string(int(attribute->num_components())) +
             " components, not " + std::to_string(components));
    return attribute;
}

}  // namespace

GltfDracoGeometry decode_gltf_draco_primitive(
    const tinygltf::Model& model, const tinygltf::Primitive& primitive, const std::string& where,
    const std::string& error_prefix, std::uint64_t max_vertices, std::uint64_t max_triangles) {
    const std::string label = where + " " + kGltfDracoCompression;
    auto fail = [&](const std::string& what) { throw Error(error_prefix + label + ": " + what); };
    const DecodedDraco decoded =
        decode_draco_mesh(model, primitive, label, error_prefix, max_vertices, max_triangles);
    const draco::Mesh& mesh = *decoded.mesh;
    const std::uint64_t vertex_count = decoded.vertex_count;
    const draco::PointAttribute* positions =
        named_attribute(decoded, "POSITION", 3, label, error_prefix);
    if (!positions) fail("needs the Draco attribute id of POSITION");
    if (positions->num_components() != 3) fail("the decoded POSITION does not have 3 components");

    GltfDracoGeometry geometry;
    geometry.positions.resize(vertex_count);
    for (draco::PointIndex p(0); p < mesh.num_points(); ++p) {
        const draco::AttributeValueIndex value = positions->mapped_index(p);
        float xyz[3];
        if (value.value() >= positions->size() || !positions->ConvertValue<float>(value, 3, xyz))
            fail("point " + std::to_string(p.value()) + " has no position");
        const Vec3f v{xyz[0], xyz[1], xyz[2]};
        if (!is_finite(v)) fail("point " + std::to_string(p.value()) + " is not finite");
        geometry.positions[p.value()] = v;
    }
    geometry.triangles.resize(mesh.num_faces());
    for (draco::FaceIndex f(0); f < mesh.num_faces(); ++f) {
        const draco::Mesh::Face& face = mesh.face(f);
        for (int c = 0; c < 3; ++c) {
            if (face[c].value() >= vertex_count)
                fail("face " + std::to_string(f.value()) + " names point " +
                     std::to_string(face[c].value()) + " of " + std::to_string(vertex_count));
            geometry.triangles[f.value()][c] = face[c].value();
        }
    }
    return geometry;
}

std::vector<std::array<float, 2>> decode_gltf_draco_texcoords(const tinygltf::Model& model,
                                                              const tinygltf::Primitive& primitive,
                                                              const std::string& name,
                                                              const std::string& where,
                                                              const std::string& error_prefix) {
    const std::string label = where + " " + kGltfDracoCompression;
    auto fail = [&](const std::string& what) { throw Error(error_prefix + label + ": " + what); };
    const DecodedDraco decoded = decode_draco_mesh(model, primitive, label, error_prefix,
                                                   std::numeric_limits<std::uint64_t>::max(),
                                                   std::numeric_limits<std::uint64_t>::max());
    const draco::PointAttribute* texcoords = named_attribute(decoded, name, 2, label, error_prefix);
    if (!texcoords) return {};
    std::vector<std::array<float, 2>> values(decoded.vertex_count);
    for (draco::PointIndex p(0); p < decoded.mesh->num_points(); ++p) {
        const draco::AttributeValueIndex value = texcoords->mapped_index(p);
        float uv[2];
        if (value.value() >= texcoords->size() || !texcoords->ConvertValue<float>(value, 2, uv))
            fail("point " + std::to_string(p.value()) + " has no " + name);
        values[p.value()] = {uv[0], uv[1]};
    }
    return values;
}

}  // namespace rebraid
