#include "rebraid/bvh/fit_inner_boxes.h"

#include <tbb/task_group.h>

#include <array>

namespace rebraid {
namespace {

/// Levels whose inner children are fitted by tasks of their own: up to 8^3 tasks, enough to
/// share a large tree's pass between threads, few enough to cost nothing on small trees.
constexpr int kTaskLevels = 3;

BBox3f fit_below(std::span<WideNode> nodes, NodeRef ref, int depth) {
    WideNode& node = nodes[ref.node_id()];
    std::array<BBox3f, kBvhWidth> fitted;
    if (depth < kTaskLevels) {
        tbb::task_group tasks;
        for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot)
            if (node.children[slot].is_inner())
                tasks.run(
                    [&, slot] { fitted[slot] = fit_below(nodes, node.children[slot], depth + 1); });
        tasks.wait();
    } else {
        for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot)
            if (node.children[slot].is_inner())
                fitted[slot] = fit_below(nodes, node.children[slot], depth + 1);
    }
    BBox3f box;
    for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot) {
        const NodeRef child = node.children[slot];
        if (child.is_inner()) node.set_child(slot, child, fitted[slot]);
        box.extend(node.child_bounds(slot));
    }
    return box;
}

}  // namespace

BBox3f fit_inner_boxes(std::span<WideNode> nodes, NodeRef root) {
    if (!root.is_inner()) return {};
    return fit_below(nodes, root, 0);
}

}  // namespace rebraid
