#include "rebraid/bvh/object_support_tables.h"

#include <tbb/parallel_for.h>

namespace rebraid {

ObjectSupportTables::ObjectSupportTables(const ObjectBvh& bvh) {
    if (bvh.root.is_empty()) return;
    std::vector<std::pair<NodeRef, BBox3f>> nodes{{bvh.root, bvh.bounds}};
    if (bvh.root.is_inner()) {
        const WideNode& root = bvh.nodes[bvh.root.node_id()];
        for (int c = 0; c < kBvhWidth && !root.children[c].is_empty(); ++c)
            if (root.children[c].is_inner())
                nodes.push_back({root.children[c], root.child_bounds(c)});
    }
    tables_.resize(nodes.size());
    tbb::parallel_for(std::size_t(0), nodes.size(), [&](std::size_t k) {
        tables_[k] = {nodes[k].first, SupportTable(bvh, nodes[k].first, nodes[k].second)};
    });
}

}  // namespace rebraid
