#include "rebraid/io/gltf_morph.h"

#include <tiny_gltf.h>

#include <cmath>

#include "rebraid/core/error.h"
#include "rebraid/io/gltf_animation_values.h"

namespace rebraid::gltf_animation {
namespace {

std::string mesh_label(const tinygltf::Model& model, std::size_t mesh_id) {
    return "mesh " + std::to_string(mesh_id) + " ('" + model.meshes[mesh_id].name + "')";
}

}  // namespace

std::size_t morph_target_count(const tinygltf::Model& model, std::size_t mesh_id,
                               const std::vector<GltfPrimitiveRange>& ranges,
                               const std::string& error_prefix) {
    const tinygltf::Mesh& mesh = model.meshes[mesh_id];
    if (ranges.empty()) return 0;
    const std::size_t count = mesh.primitives[ranges.front().gltf_primitive].targets.size();
    for (const GltfPrimitiveRange& range : ranges) {
        const std::size_t here = mesh.primitives[range.gltf_primitive].targets.size();
        if (here != count)
            throw Error(error_prefix + mesh_label(model, mesh_id) + " primitive " +
                        std::to_string(range.gltf_primitive) + " has " + std::to_string(here) +
                        " morph targets, primitive " +
                        std::to_string(ranges.front().gltf_primitive) + " has " +
                        std::to_string(count) + ": every primitive needs the same number");
    }
    if (count > 0 && !mesh.weights.empty() && mesh.weights.size() != count)
        throw Error(error_prefix + mesh_label(model, mesh_id) + " has " +
                    std::to_string(mesh.weights.size()) + " default weights for " +
                    std::to_string(count) + " morph targets");
    return count;
}

MorphTargets read_morph_targets(const tinygltf::Model& model, std::size_t mesh_id,
                                const std::vector<GltfPrimitiveRange>& ranges,
                                std::size_t vertex_count, const std::string& error_prefix) {
    const tinygltf::Mesh& mesh = model.meshes[mesh_id];
    MorphTargets targets;
    targets.target_count = morph_target_count(model, mesh_id, ranges, error_prefix);
    const std::size_t count = targets.target_count;
    targets.deltas.assign(vertex_count * count, Vec3f{});
    targets.default_weights.assign(count, 0.0f);
    for (std::size_t t = 0; t < count && !mesh.weights.empty(); ++t) {
        if (!std::isfinite(mesh.weights[t]))
            throw Error(error_prefix + mesh_label(model, mesh_id) + " default weight " +
                        std::to_string(t) + " is not finite");
        targets.default_weights[t] = float(mesh.weights[t]);
    }

    for (const GltfPrimitiveRange& range : ranges) {
        const tinygltf::Primitive& primitive = mesh.primitives[range.gltf_primitive];
        for (std::size_t t = 0; t < count; ++t) {
            const auto position = primitive.targets[t].find("POSITION");
            if (position == primitive.targets[t].end()) continue;  // this target moves nothing
            const std::string role = mesh_label(model, mesh_id) + " primitive " +
                                     std::to_string(range.gltf_primitive) + " morph target " +
                                     std::to_string(t) + " POSITION";
            const std::vector<float> deltas =
                read_float_accessor(model, position->second, TINYGLTF_TYPE_VEC3,
                                    FloatEncoding::kFloatOrNormalized, role, error_prefix);
            if (deltas.size() != 3 * range.vertex_count)
                throw Error(error_prefix + role + " has " + std::to_string(deltas.size() / 3) +
                            " elements, the primitive has " + std::to_string(range.vertex_count) +
                            " vertices");
            for (std::size_t v = 0; v < range.vertex_count; ++v)
                targets.deltas[(range.first_vertex + v) * count + t] = {
                    deltas[3 * v], deltas[3 * v + 1], deltas[3 * v + 2]};
        }
    }
    return targets;
}

}  // namespace rebraid::gltf_animation
