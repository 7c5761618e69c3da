#include "rebraid/io/gltf_draco.h"

#include <draco/compression/decode.h>
#include <tiny_gltf.h>

#include <cmath>

#include "rebraid/core/error.h"
#include "rebraid/io/gltf_accessor.h"

namespace rebraid {

bool uses_gltf_draco(const tinygltf::Primitive& primitive) {
    return primitive.extensions.count(kGltfDracoCompression) != 0;
}

GltfDracoGeometry decode_gltf_draco_primitive(
    const tinygltf::Model& model, const tinygltf::Primitive& primitive, const std::string& where,
    const std::string& error_prefix, std::uint64_t max_vertices, std::uint64_t max_triangles) {
    const std::string label = where + " " + kGltfDracoCompression;
    auto fail = [&](const std::string& what) { throw Error(error_prefix + label + ": " + what); };
    const tinygltf::Value& extension = primitive.extensions.at(kGltfDracoCompression);
    if (!extension.IsObject() || !extension.Has("bufferView") ||
        !extension.Get("bufferView").IsInt() || !extension.Has("attributes") ||
        !extension.Get("attributes").IsObject())
        fail("needs a bufferView index and an attributes object");
    const tinygltf::Value& position_id = extension.Get("attributes").Get("POSITION");
    if (!position_id.IsInt() || position_id.GetNumberAsInt() < 0)
        fail("needs the Draco attribute id of POSITION");
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
    const std::uint64_t vertex_count = accessor_count(position->second, "POSITION");
    if (primitive.indices < 0) fail("the primitive has no indices accessor");
    const std::uint64_t index_count = accessor_count(primitive.indices, "indices");
    if (vertex_count > max_vertices || index_count / 3 > max_triangles)
        fail("declares " + std::to_string(vertex_count) + " vertices and " +
             std::to_string(index_count / 3) + " triangles, more than max_vertices = " +
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
    auto decoded = decoder.DecodeMeshFromBuffer(&compressed);
    if (!decoded.ok()) fail("corrupt Draco data (" + decoded.status().error_msg_string() + ")");
    const draco::Mesh& mesh = *decoded.value();
    const draco::PointAttribute* positions =
        mesh.GetAttributeByUniqueId(std::uint32_t(position_id.GetNumberAsInt()));
    if (!positions)
        fail("the decoded mesh has no attribute " + std::to_string(position_id.GetNumberAsInt()));
    if (positions->num_components() != 3) fail("the decoded POSITION does not have 3 components");
    if (mesh.num_points() != vertex_count || std::uint64_t(mesh.num_faces()) * 3 != index_count)
        fail("decoded " + std::to_string(mesh.num_points()) + " points and " +
             std::to_string(mesh.num_faces()) + " triangles, the accessors say " +
             std::to_string(vertex_count) + " and " + std::to_string(index_count / 3));

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

}  // namespace rebraid
