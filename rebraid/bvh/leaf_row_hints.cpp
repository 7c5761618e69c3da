#include "rebraid/bvh/leaf_row_hints.h"

#include <algorithm>

#include <tbb/parallel_for.h>

#include "rebraid/bvh/leaf_rows.h"

namespace rebraid {
// A leaf-order position fits below the line count, as it fits a NodeRef's first field.
static_assert(kLeafRowHintLineShift == NodeRef::kCountShift);

std::uint32_t leaf_row_hint(const WideNode& node) {
    std::uint32_t first = 0, end = 0;
    bool found = false;
    for (const NodeRef child : node.children) {
        if (!child.is_leaf()) continue;
        if (!found) {
            first = child.first_prim();
            end = first + child.prim_count();
            found = true;
        } else if (child.first_prim() == end) {
            end += child.prim_count();
        } else {
            break;
        }
    }
    if (!found) return 0;
    const std::uint32_t bytes = (end - first) * kRowFloatsPerTriangle * sizeof(float);
    const std::uint32_t lines = std::min(kMaxLeafRowHintLines, bytes / 64 + 1);
    return (lines << kLeafRowHintLineShift) | first;
}

void write_leaf_row_hints(std::vector<WideNode>& nodes) {
    tbb::parallel_for(std::size_t(0), nodes.size(), [&](std::size_t n) {
        WideNode& node = nodes[n];
        for (int slot = 0; slot < kBvhWidth; ++slot) {
            const NodeRef child = node.children[slot];
            node.leaf_row_hints[slot] =
                child.is_inner() ? leaf_row_hint(nodes[child.node_id()]) : 0u;
        }
    });
}

}  // namespace rebraid
