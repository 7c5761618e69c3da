#pragma once

// EXT_mesh_gpu_instancing (internal to rebraid::io): a node with the extension stands for
// `count` placements of its mesh, each the node's world transform times T * R * S of one
// element of the TRANSLATION / ROTATION / SCALE accessors.

#include <cstdint>
#include <string>

#include "rebraid/io/gltf_accessor.h"
#include "rebraid/io/gltf_animation_math.h"

namespace rebraid {

inline constexpr const char* kGltfGpuInstancing = "EXT_mesh_gpu_instancing";

/// The instance transforms of one node's EXT_mesh_gpu_instancing. Construction checks the
/// extension's shape and its accessors (types, counts, bounds); element() checks each value.
class GltfGpuInstancing {
public:
    /// True when node `node` of `model` carries the extension.
    static bool is_used_by(const tinygltf::Model& model, std::size_t node);

    /// Reads node `node`'s extension. Throws rebraid::Error starting with `error_prefix`
    /// for an extension that is not an object, no or unknown-typed attributes, an accessor
    /// of the wrong type or component type, past its buffer, attributes of different counts,
    /// a count of zero, or a node without a mesh.
    GltfGpuInstancing(const tinygltf::Model& model, std::size_t node,
                      const std::string& error_prefix);

    std::uint64_t count() const { return count_; }

    /// T * R * S of element `i` (< count()); a missing attribute is the identity. Throws
    /// rebraid::Error for a non-finite value or a rotation that is not a unit quaternion.
    gltf_animation::Affine3d element(std::uint64_t i) const;

private:
    struct Attribute {
        GltfElementRange range;
        int component_type = 0;
        bool normalized = false;
    };
    [[noreturn]] void fail(const std::string& what) const;
    Attribute read_attribute(const tinygltf::Model& model, const tinygltf::Value& attributes,
                             const char* name, int type, bool allow_normalized_integers);
    gltf_animation::Vec3d vec3(const Attribute& attribute, std::uint64_t i, const char* name) const;

    std::string error_prefix_;
    std::string node_label_;
    std::uint64_t count_ = 0;
    bool has_count_ = false;
    Attribute translation_, rotation_, scale_;
};

}  // namespace rebraid
