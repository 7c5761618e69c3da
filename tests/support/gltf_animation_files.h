#pragma once

// Helpers for animation tests: keyframe accessors, samplers, channels, skins and morph
// targets on top of the glTF test writer of gltf_test_files.h.

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <numbers>

#include "rebraid/io/gltf_animation.h"
#include "rebraid/io/gltf_scene.h"
#include "support/gltf_test_files.h"

namespace rebraid::test {

inline constexpr int kByte = 5120;
inline constexpr int kShort = 5122;

/// Tightly packed float accessor of `type` ("SCALAR", "VEC3", "VEC4", "MAT4") over `values`.
inline int add_floats(GltfTestFile& file, const std::vector<float>& values,
                      const std::string& type) {
    const std::size_t components = type == "SCALAR" ? 1
                                   : type == "VEC3" ? 3
                                   : type == "VEC4" ? 4
                                                    : 16;
    const int view = file.add_view(values.data(), values.size() * sizeof(float));
    return file.add_accessor(view, kFloat, values.size() / components, type);
}

/// Integer accessor of `type` with components stored as `component_type` (byte / short,
/// signed or not), optionally flagged normalized.
inline int add_integers(GltfTestFile& file, const std::vector<std::int32_t>& values,
                        int component_type, const std::string& type, bool normalized) {
    const std::size_t size = component_type == kUnsignedByte || component_type == kByte ? 1 : 2;
    const std::size_t components = type == "SCALAR" ? 1 : type == "VEC3" ? 3 : 4;
    std::vector<unsigned char> bytes(values.size() * size);
    for (std::size_t i = 0; i < values.size(); ++i) {
        if (size == 1) {
            const std::int8_t v8 = std::int8_t(values[i]);
            const std::uint8_t u8 = std::uint8_t(values[i]);
            bytes[i] = component_type == kByte ? std::uint8_t(v8) : u8;
        } else {
            const std::uint16_t u16 = std::uint16_t(values[i]);  // two's complement for shorts
            std::memcpy(&bytes[2 * i], &u16, 2);                 // little-endian host
        }
    }
    const int accessor = file.add_accessor(file.add_view(bytes.data(), bytes.size()),
                                           component_type, values.size() / components, type);
    if (normalized) file.json["accessors"][accessor]["normalized"] = true;
    return accessor;
}

/// A one-channel animation driving `path` of `node`: key `times`, `values` (already
/// including tangents for CUBICSPLINE), output accessor of `type`.
inline int add_channel_animation(GltfTestFile& file, int node, const std::string& path,
                                 const std::vector<float>& times, const std::vector<float>& values,
                                 const std::string& type,
                                 const std::string& interpolation = "LINEAR") {
    const int input = add_floats(file, times, "SCALAR");
    const int output = add_floats(file, values, type);
    nlohmann::json animation = {
        {"name", path + " of node " + std::to_string(node)},
        {"samplers", {{{"input", input}, {"output", output}, {"interpolation", interpolation}}}},
        {"channels", {{{"sampler", 0}, {"target", {{"node", node}, {"path", path}}}}}}};
    file.json["animations"].push_back(animation);
    return int(file.json["animations"].size()) - 1;
}

/// One triangle (0,0,0), (1,0,0), (0,1,0) as a mesh; returns its index.
inline int add_triangle_mesh(GltfTestFile& file) {
    const int positions = file.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    return file.add_mesh({primitive(positions)}, "triangle");
}

/// Quaternion (x, y, z, w) of a rotation by `degrees` about +z.
inline std::vector<float> z_rotation(double degrees) {
    const double half = degrees * std::numbers::pi / 360.0;
    return {0.0f, 0.0f, float(std::sin(half)), float(std::cos(half))};
}

inline std::vector<float> concat(std::vector<float> a, const std::vector<float>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
}

/// How the two-joint skin file stores its influences, and what else uses its mesh.
struct TwoJointSkin {
    int joint_type = kUnsignedShort;  ///< kUnsignedByte or kUnsignedShort
    int weight_type = kFloat;         ///< kFloat, or normalized kUnsignedByte / kUnsignedShort
    /// Vertex 1's weights on joints 0 and 1, as stored (floats, or raw integers).
    std::vector<std::int32_t> raw_vertex_1_weights = {1, 1};
    bool has_inverse_bind_matrices = true;
    int extra_skinned_nodes = 0;      ///< more roots skinning the same mesh with the same skin
    bool has_static_user = false;     ///< one more root using the mesh without a skin
    std::int32_t vertex_2_joint = 1;  ///< the joint vertex 2 follows (an index past the skin: bad)
    /// Gives the mesh one morph target moving vertex 2 by (1, 0, 0), weight 1 on node 0.
    bool has_morph_target = false;
};

/// Vertex 1's weight on joint 1 after the animator rescales the pair to sum 1.
inline double vertex_1_joint_1_share(const TwoJointSkin& skin) {
    return double(skin.raw_vertex_1_weights[1]) /
           double(skin.raw_vertex_1_weights[0] + skin.raw_vertex_1_weights[1]);
}

/// Skin file: node 0 holds mesh 0 (vertices (0,0,0), (2,0,0), (2,0,1)) with skin 0 and a
/// translation (100, 0, 0) that posing must ignore. Joint 0 is root node 1 at the origin,
/// joint 1 its child node 2 at (1, 0, 0). Vertex 0 follows joint 0 (next to a zero-weight
/// joint index 7, past the skin, which must be ignored), vertex 1 is split between joints 0
/// and 1, vertex 2 follows joint 1. Inverse bind matrices (when present) invert each joint's
/// rest world transform: I and T(-1, 0, 0). Joint 1 turns from 0 to 90 degrees about z over
/// 1 s (LINEAR). Extra roots (nodes 3, 4, ...) follow `skin`.
inline GltfTestFile two_joint_skin_file(const TwoJointSkin& skin) {
    GltfTestFile file;
    const int positions = file.add_positions({{0, 0, 0}, {2, 0, 0}, {2, 0, 1}});
    const int joints = add_integers(file, {0, 7, 0, 0, 0, 1, 0, 0, skin.vertex_2_joint, 0, 0, 0},
                                    skin.joint_type, "VEC4", false);
    const std::int32_t one = skin.weight_type == kUnsignedByte    ? 255
                             : skin.weight_type == kUnsignedShort ? 65535
                                                                  : 1;
    const std::vector<std::int32_t> raw_weights = {
        one, 0, 0, 0, skin.raw_vertex_1_weights[0], skin.raw_vertex_1_weights[1], 0, 0,
        one, 0, 0, 0};
    int weights = 0;
    if (skin.weight_type == kFloat) {
        const std::vector<float> as_float(raw_weights.begin(), raw_weights.end());
        weights = add_floats(file, as_float, "VEC4");
    } else {
        weights = add_integers(file, raw_weights, skin.weight_type, "VEC4", true);
    }
    nlohmann::json skinned_primitive = primitive(positions);
    skinned_primitive["attributes"]["JOINTS_0"] = joints;
    skinned_primitive["attributes"]["WEIGHTS_0"] = weights;
    if (skin.has_morph_target)
        skinned_primitive["targets"] = {
            {{"POSITION", file.add_positions({{0, 0, 0}, {0, 0, 0}, {1, 0, 0}})}}};
    const int mesh = file.add_mesh({skinned_primitive}, "skinned");

    nlohmann::json skin_json = {{"joints", {1, 2}}};
    if (skin.has_inverse_bind_matrices) {
        std::vector<float> matrices = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0,  0, 0, 1,
                                       1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -1, 0, 0, 1};
        skin_json["inverseBindMatrices"] = add_floats(file, matrices, "MAT4");
    }
    file.json["skins"].push_back(skin_json);

    file.add_node({{"mesh", mesh}, {"skin", 0}, {"translation", {100, 0, 0}}});  // 0
    if (skin.has_morph_target) file.json["nodes"][0]["weights"] = {1.0};
    file.add_node({{"children", {2}}, {"name", "joint 0"}});           // 1
    file.add_node({{"translation", {1, 0, 0}}, {"name", "joint 1"}});  // 2
    std::vector<int> roots = {0, 1};
    for (int extra = 0; extra < skin.extra_skinned_nodes; ++extra)
        roots.push_back(file.add_node({{"mesh", mesh}, {"skin", 0}}));
    if (skin.has_static_user) roots.push_back(file.add_node({{"mesh", mesh}}));
    file.add_scene(roots);
    add_channel_animation(file, 2, "rotation", {0, 1}, concat(z_rotation(0), z_rotation(90)),
                          "VEC4");
    return file;
}

inline std::string write_two_joint_skin_file(const std::string& name, const TwoJointSkin& skin) {
    return two_joint_skin_file(skin).write_glb(name);
}

/// Morph file base: mesh 0 is the triangle (0,0,0), (1,0,0), (0,1,0) with two targets;
/// target 0 moves vertex 0 by (0, 0, 2), target 1 moves vertex 1 by (0, 4, 0). `mesh_weights`
/// become the mesh's default weights unless empty. Tests add nodes, scenes and animations.
inline GltfTestFile morph_file_base(const std::vector<double>& mesh_weights) {
    GltfTestFile file;
    const int positions = file.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    const int target_0 = file.add_positions({{0, 0, 2}, {0, 0, 0}, {0, 0, 0}});
    const int target_1 = file.add_positions({{0, 0, 0}, {0, 4, 0}, {0, 0, 0}});
    nlohmann::json morphed = primitive(positions);
    morphed["targets"] = {{{"POSITION", target_0}}, {{"POSITION", target_1}}};
    file.add_mesh({morphed}, "morphed");
    if (!mesh_weights.empty()) file.json["meshes"][0]["weights"] = mesh_weights;
    return file;
}

/// Loads `path` keeping the model, as the animator needs.
inline GltfLoadResult load_animated(const std::string& path) {
    GltfLoadOptions options;
    options.keep_model = true;
    return load_gltf_scene_with_report(path, options);
}

}  // namespace rebraid::test
