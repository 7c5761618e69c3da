#pragma once

// KHR_draco_mesh_compression (internal to rebraid::io): a primitive whose positions,
// triangles and possibly other attributes are stored as one Draco-compressed mesh.

#include <array>
#include <string>
#include <vector>

#include "rebraid/core/scene.h"

namespace tinygltf {
class Model;
struct Primitive;
}  // namespace tinygltf

namespace rebraid {

inline constexpr const char* kGltfDracoCompression = "KHR_draco_mesh_compression";

/// A decoded primitive: its points in Draco's point order (which the glTF accessors of the
/// primitive follow) and its triangles in the decoded face order (a triangle's PrimId within
/// the primitive is its face index).
struct GltfDracoGeometry {
    std::vector<Vec3f> positions;
    std::vector<Triangle> triangles;
};

/// True when `primitive` carries KHR_draco_mesh_compression.
bool uses_gltf_draco(const tinygltf::Primitive& primitive);

/// Decodes `primitive`'s Draco mesh. Throws rebraid::Error starting with `error_prefix` and
/// naming `where` (the primitive) for a malformed extension, a bufferView past its buffer, a
/// mode other than TRIANGLES, data Draco rejects, a POSITION attribute missing from the
/// decoded mesh or not three numbers, a non-finite position, a face naming a missing point,
/// or decoded counts that differ from the primitive's POSITION / indices accessor counts
/// (the extension requires them equal). Those accessor counts are checked against
/// `max_vertices` and `max_triangles` before anything is decoded.
GltfDracoGeometry decode_gltf_draco_primitive(
    const tinygltf::Model& model, const tinygltf::Primitive& primitive, const std::string& where,
    const std::string& error_prefix, std::uint64_t max_vertices, std::uint64_t max_triangles);

/// The texture coordinates the extension of `primitive` names `name` (e.g. "TEXCOORD_0"),
/// decoded from its Draco mesh in Draco's point order (the order of the primitive's decoded
/// positions); empty when the extension does not name that attribute (the primitive then
/// stores it uncompressed, as any attribute). Throws rebraid::Error as
/// decode_gltf_draco_primitive does, and for an attribute of fewer than 2 components.
std::vector<std::array<float, 2>> decode_gltf_draco_texcoords(const tinygltf::Model& model,
                                                              const tinygltf::Primitive& primitive,
                                                              const std::string& name,
                                                              const std::string& where,
                                                              const std::string& error_prefix);

}  // namespace rebraid
