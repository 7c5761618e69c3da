#include "rebraid/bvh/fit_inner_boxes.h"

#include <tbb/task_group.h>

#include <array>
#include <cstddef>

namespace rebraid {
namespace {

/// Levels whose inner children are fitted by tasks of their own in a large tree: up to 8^3
/// tasks, enough to share the pass between threads.
constexpr int kTaskLevels = 3;
/// Trees of fewer nodes are fitted on one thread: their pass is shorter than the tasks' set-up.
constexpr std::size_t kTaskTreeNodes = 4096;

/// `task_levels`: the levels below `ref` whose children are fitted by tasks.
BBox3f fit_below(std::span<WideNode> nodes, NodeRef ref, int depth, int task_levels) {
    WideNode& node = nodes[ref.node_id()];
    std::array<BBox3f, kBvhWidth> fitted;
    if (depth < task_levels) {
        tbb::task_group tasks;
        for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot)
            if (node.children[slot].is_inner())
                tasks.run([&, slot] {
                    fitted[slot] = fit_below(nodes, node.children[slot], depth + 1, task_levels);
                });
        tasks.wait();
    } else {
        for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot)
            if (node.children[slot].is_inner())
                fitted[slot] = fit_below(nodes, node.children[slot], depth + 1, task_levels);
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
    return fit_below(nodes, root, 0, nodes.size() >= kTaskTreeNodes ? kTaskLevels : 0);
}

}  // namespace rebraid
