#include "rebraid/io/gltf_animation_nodes.h"

#include <tiny_gltf.h>

#include <cmath>

#include "rebraid/core/error.h"

namespace rebraid::gltf_animation {
namespace {

std::string node_label(const tinygltf::Model& model, std::size_t n) {
    return "node " + std::to_string(n) + " ('" + model.nodes[n].name + "')";
}

/// Rest pose of node `n`: its local transform and, for TRS nodes, the TRS itself.
void read_rest_pose(const tinygltf::Model& model, std::size_t n, const std::string& error_prefix,
                    NodeTrs& trs, Affine3d& local) {
    const tinygltf::Node& node = model.nodes[n];
    auto check = [&](const std::vector<double>& values, std::size_t expected, const char* what) {
        if (!values.empty() && values.size() != expected)
            throw Error(error_prefix + node_label(model, n) + " has a " + what + " of " +
                        std::to_string(values.size()) + " numbers, expected " +
                        std::to_string(expected));
        for (double value : values)
            if (!std::isfinite(value))
                throw Error(error_prefix + node_label(model, n) + " has a non-finite " + what +
                            " value");
    };
    check(node.matrix, 16, "matrix");
    check(node.translation, 3, "translation");
    check(node.rotation, 4, "rotation");
    check(node.scale, 3, "scale");
    if (!node.translation.empty())
        trs.translation = {node.translation[0], node.translation[1], node.translation[2]};
    if (!node.rotation.empty())
        trs.rotation = {node.rotation[0], node.rotation[1], node.rotation[2], node.rotation[3]};
    if (!node.scale.empty()) trs.scale = {node.scale[0], node.scale[1], node.scale[2]};
    local = node.matrix.empty() ? Affine3d::from_trs(trs)
                                : Affine3d::from_column_major(node.matrix.data());
}

}  // namespace

NodeHierarchy read_node_hierarchy(const tinygltf::Model& model, const std::string& error_prefix) {
    const std::size_t node_count = model.nodes.size();
    NodeHierarchy hierarchy;
    hierarchy.parent.assign(node_count, kNoParent);
    hierarchy.rest_trs.resize(node_count);
    hierarchy.rest_local.resize(node_count);
    hierarchy.rest_world.resize(node_count);
    for (std::size_t n = 0; n < node_count; ++n) {
        read_rest_pose(model, n, error_prefix, hierarchy.rest_trs[n], hierarchy.rest_local[n]);
        for (int child : model.nodes[n].children) {
            if (child < 0 || std::size_t(child) >= node_count)
                throw Error(error_prefix + node_label(model, n) + " lists child " +
                            std::to_string(child) + ", file has " + std::to_string(node_count) +
                            " nodes");
            if (hierarchy.parent[std::size_t(child)] != kNoParent)
                throw Error(error_prefix + node_label(model, std::size_t(child)) +
                            " has two parents (node " +
                            std::to_string(hierarchy.parent[std::size_t(child)]) + " and node " +
                            std::to_string(n) + "): the node hierarchy must be a forest");
            hierarchy.parent[std::size_t(child)] = std::uint32_t(n);
        }
    }

    // Depth-first from the roots with an explicit stack (deep chains must not overflow the
    // call stack). With one parent per node, nodes never reached lie on a cycle.
    hierarchy.order.reserve(node_count);
    std::vector<std::uint32_t> stack;
    for (std::size_t root = 0; root < node_count; ++root) {
        if (hierarchy.parent[root] != kNoParent) continue;
        stack.push_back(std::uint32_t(root));
        while (!stack.empty()) {
            const std::uint32_t n = stack.back();
            stack.pop_back();
            hierarchy.order.push_back(n);
            const std::uint32_t parent = hierarchy.parent[n];
            hierarchy.rest_world[n] = parent == kNoParent
                                          ? hierarchy.rest_local[n]
                                          : hierarchy.rest_world[parent] * hierarchy.rest_local[n];
            const std::vector<int>& children = model.nodes[n].children;
            for (auto child = children.rbegin(); child != children.rend(); ++child)
                stack.push_back(std::uint32_t(*child));
        }
    }
    if (hierarchy.order.size() != node_count) {
        std::vector<bool> reached(node_count, false);
        for (std::uint32_t n : hierarchy.order) reached[n] = true;
        std::size_t first = 0;
        while (reached[first]) ++first;
        throw Error(error_prefix + node_label(model, first) +
                    " is part of a node cycle: the node hierarchy must be a forest");
    }
    return hierarchy;
}

std::vector<std::uint32_t> nodes_below(const NodeHierarchy& hierarchy,
                                       const std::vector<bool>& is_animated) {
    std::vector<bool> is_below(hierarchy.node_count(), false);
    std::vector<std::uint32_t> nodes;
    for (std::uint32_t n : hierarchy.order) {  // parents first, so one pass suffices
        const std::uint32_t parent = hierarchy.parent[n];
        is_below[n] = is_animated[n] || (parent != kNoParent && is_below[parent]);
        if (is_below[n]) nodes.push_back(n);
    }
    return nodes;
}

}  // namespace rebraid::gltf_animation
