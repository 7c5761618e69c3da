#pragma once

#include <cstdint>
#include <vector>

#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/types.h"

namespace rebraid {

/// What a top-level leaf points at: a node (inner or leaf) of the BVH of an instance's mesh.
/// A plain two-level top has one item per instance at its object root; a re-braided top has
/// items deeper in the object BVHs (the BRefs left after opening, paper §3.2).
struct TopLevelItem {
    InstanceId instance_id = 0;
    NodeRef object_node;
};

/// A top-level BVH in the shared wide layout; its leaf references index `items`.
struct TopLevelBvh {
    std::vector<WideNode> nodes;
    NodeRef root = NodeRef::empty();
    BBox3f bounds;
    std::vector<TopLevelItem> items;
    /// World bounds of each item (for statistics and validation; traversal does not read it).
    std::vector<BBox3f> item_bounds;
    /// Some items may name part of an object BVH leaf (RebraidSettings::open_leaves opens
    /// leaves into single triangles). Traversal then reads leaf items' triangles from the
    /// corner storage: the pre-arranged leaf rows address whole leaves only.
    bool has_partial_leaves = false;
    double build_ms = 0.0;

    std::uint64_t memory_bytes() const {
        return nodes.size() * sizeof(WideNode) + items.size() * sizeof(TopLevelItem) +
               item_bounds.size() * sizeof(BBox3f);
    }
};

}  // namespace rebraid
