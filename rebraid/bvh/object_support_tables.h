#pragma once

#include <utility>
#include <vector>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/support_table.h"
#include "rebraid/bvh/wide_node.h"

namespace rebraid {

/// SupportTables of the top of one object BVH: its root and the root's inner children, the
/// nodes whose world boxes a re-braiding build asks for once per instance of the mesh (the
/// BRef each instance starts with, and the BRefs opening it makes). Built for meshes with
/// many instances, where the tables cost less than searching the BVH once per instance.
class ObjectSupportTables {
public:
    /// No tables.
    ObjectSupportTables() = default;
    /// The tables of `bvh`'s root and its inner children, built in parallel.
    explicit ObjectSupportTables(const ObjectBvh& bvh);

    /// The table of `node`, or nullptr when it has none.
    const SupportTable* find(NodeRef node) const {
        for (const auto& [table_node, table] : tables_)
            if (table_node == node) return &table;
        return nullptr;
    }

private:
    std::vector<std::pair<NodeRef, SupportTable>> tables_;
};

}  // namespace rebraid
