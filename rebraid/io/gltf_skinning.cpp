#include "rebraid/io/gltf_skinning.h"

#include <tiny_gltf.h>

#include <algorithm>

#include "rebraid/core/error.h"
#include "rebraid/io/gltf_animation_values.h"

namespace rebraid::gltf_animation {

Skin read_skin(const tinygltf::Model& model, int skin_id, const std::string& error_prefix) {
    if (skin_id < 0 || std::size_t(skin_id) >= model.skins.size())
        throw Error(error_prefix + "skin " + std::to_string(skin_id) +
                    " does not exist, file has " + std::to_string(model.skins.size()) + " skins");
    const tinygltf::Skin& gltf_skin = model.skins[std::size_t(skin_id)];
    const std::string label = "skin " + std::to_string(skin_id) + " ('" + gltf_skin.name + "')";
    Skin skin;
    for (std::size_t j = 0; j < gltf_skin.joints.size(); ++j) {
        const int node = gltf_skin.joints[j];
        if (node < 0 || std::size_t(node) >= model.nodes.size())
            throw Error(error_prefix + label + " joint " + std::to_string(j) +
                        " references missing node " + std::to_string(node) + ", file has " +
                        std::to_string(model.nodes.size()) + " nodes");
        skin.joints.push_back(std::uint32_t(node));
    }
    skin.inverse_bind_matrices.resize(skin.joints.size());  // identity by default
    if (gltf_skin.inverseBindMatrices >= 0) {
        const std::vector<float> matrices = read_float_accessor(
            model, gltf_skin.inverseBindMatrices, TINYGLTF_TYPE_MAT4, FloatEncoding::kFloatOnly,
            "inverseBindMatrices of " + label, error_prefix);
        if (matrices.size() < 16 * skin.joints.size())
            throw Error(error_prefix + label + " has " + std::to_string(matrices.size() / 16) +
                        " inverse bind matrices for " + std::to_string(skin.joints.size()) +
                        " joints");
        for (std::size_t j = 0; j < skin.joints.size(); ++j)
            skin.inverse_bind_matrices[j] = Affine3d::from_column_major(&matrices[16 * j]);
    }
    return skin;
}

SkinInfluences read_skin_influences(const tinygltf::Model& model, std::size_t mesh_id,
                                    const std::vector<GltfPrimitiveRange>& ranges,
                                    std::size_t vertex_count, const std::string& error_prefix) {
    const tinygltf::Mesh& mesh = model.meshes[mesh_id];
    const std::string mesh_label = "mesh " + std::to_string(mesh_id) + " ('" + mesh.name + "')";
    auto attribute = [](const tinygltf::Primitive& primitive, const std::string& name) {
        const auto found = primitive.attributes.find(name);
        return found == primitive.attributes.end() ? -1 : found->second;
    };
    auto set_count = [&](const tinygltf::Primitive& primitive) {
        std::size_t sets = 0;
        while (attribute(primitive, "JOINTS_" + std::to_string(sets)) >= 0 &&
               attribute(primitive, "WEIGHTS_" + std::to_string(sets)) >= 0)
            ++sets;
        return sets;
    };

    SkinInfluences influences;
    for (const GltfPrimitiveRange& range : ranges)
        influences.influence_count = std::max(influences.influence_count,
                                              4 * set_count(mesh.primitives[range.gltf_primitive]));
    influences.joints.assign(vertex_count * influences.influence_count, 0);
    influences.weights.assign(vertex_count * influences.influence_count, 0.0f);
    const std::size_t stride = influences.influence_count;

    for (const GltfPrimitiveRange& range : ranges) {
        const tinygltf::Primitive& primitive = mesh.primitives[range.gltf_primitive];
        const std::string where = mesh_label + " primitive " + std::to_string(range.gltf_primitive);
        const std::size_t sets = set_count(primitive);
        if (sets == 0)
            throw Error(error_prefix + where +
                        " has no JOINTS_0 / WEIGHTS_0 but is used by a skinned node");
        for (std::size_t set = 0; set < sets; ++set) {
            // Appended rather than "_" + to_string(): GCC 12 warns falsely (-Wrestrict) there.
            std::string suffix = "_";
            suffix += std::to_string(set);
            const std::vector<std::uint32_t> joints = read_joint_accessor(
                model, attribute(primitive, "JOINTS" + suffix), TINYGLTF_TYPE_VEC4,
                "JOINTS" + suffix + " of " + where, error_prefix);
            const std::vector<float> weights =
                read_float_accessor(model, attribute(primitive, "WEIGHTS" + suffix),
                                    TINYGLTF_TYPE_VEC4, FloatEncoding::kFloatOrUnsignedNormalized,
                                    "WEIGHTS" + suffix + " of " + where, error_prefix);
            if (joints.size() != 4 * range.vertex_count || weights.size() != 4 * range.vertex_count)
                throw Error(error_prefix + where + ": JOINTS" + suffix + " has " +
                            std::to_string(joints.size() / 4) + " and WEIGHTS" + suffix + " " +
                            std::to_string(weights.size() / 4) +
                            " elements, expected one per vertex (" +
                            std::to_string(range.vertex_count) + ")");
            for (std::size_t v = 0; v < range.vertex_count; ++v)
                for (std::size_t i = 0; i < 4; ++i) {
                    const std::size_t slot = (range.first_vertex + v) * stride + 4 * set + i;
                    influences.joints[slot] = joints[4 * v + i];
                    influences.weights[slot] = weights[4 * v + i];
                }
        }
    }

    // Weights should sum to 1; exporters' rounding (and normalized bytes) leave them slightly
    // off, so they are rescaled. Joints of zero weights are never read: set them to 0, since
    // files often leave arbitrary indices there.
    for (std::size_t v = 0; v < vertex_count; ++v) {
        std::uint32_t* joints = &influences.joints[v * stride];
        float* weights = &influences.weights[v * stride];
        double sum = 0;
        for (std::size_t i = 0; i < stride; ++i) sum += weights[i];
        if (!(sum > 0)) {
            for (std::size_t i = 0; i < stride; ++i) joints[i] = 0, weights[i] = 0;
            if (stride > 0) joints[0] = kUnweightedJoint, weights[0] = 1;
            continue;
        }
        for (std::size_t i = 0; i < stride; ++i) {
            weights[i] = float(weights[i] / sum);
            if (weights[i] == 0.0f)
                joints[i] = 0;
            else
                influences.required_joint_count =
                    std::max(influences.required_joint_count, joints[i] + 1);
        }
    }
    return influences;
}

}  // namespace rebraid::gltf_animation
