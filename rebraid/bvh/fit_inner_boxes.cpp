#include "rebraid/bvh/fit_inner_boxes.h"

namespace rebraid {

BBox3f fit_inner_boxes(std::span<WideNode> nodes, NodeRef root) {
    if (!root.is_inner()) return {};
    WideNode& node = nodes[root.node_id()];
    BBox3f box;
    for (int slot = 0; slot < kBvhWidth && !node.children[slot].is_empty(); ++slot) {
        const NodeRef child = node.children[slot];
        if (child.is_inner()) node.set_child(slot, child, fit_inner_boxes(nodes, child));
        box.extend(node.child_bounds(slot));
    }
    return box;
}

}  // namespace rebraid
