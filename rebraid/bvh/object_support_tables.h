#pragma once

#include <cstddef>
#include <memory>
#include <mutex>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/support_table.h"
#include "rebraid/bvh/wide_node.h"

namespace rebraid {

/// SupportTables of the top of one object BVH: its root and the root's inner children, the
/// nodes whose world boxes a re-braiding build asks for once per instance of the mesh (the
/// BRef each instance starts with, and the BRefs opening it makes). Built for meshes with
/// many instances, where the tables cost less than searching the BVH once per instance.
///
/// The root's table is made at construction, a child's when it is first asked for: every
/// instance starts at the root, while children are asked for only where a BRef to the root
/// opens, and on scenes where nothing opens (forests, cities) their tables were most of the
/// cost. A table's values do not depend on when or by which thread it is made, so the
/// boxes, and the build, are the same either way. Safe to query from several threads.
class ObjectSupportTables {
public:
    /// No tables.
    ObjectSupportTables() = default;
    /// The table of `bvh`'s root now, those of its inner children on demand (`bvh` must
    /// outlive this object and stay unchanged).
    explicit ObjectSupportTables(const ObjectBvh& bvh);

    /// The table of `node`, made now when it is a child's asked for the first time; nullptr
    /// when `node` has none.
    const SupportTable* find(NodeRef node) const;

private:
    struct Entry {
        NodeRef node;
        BBox3f box;  ///< the node's object-space box
        mutable std::once_flag made;
        mutable SupportTable table;
    };
    const ObjectBvh* bvh_ = nullptr;
    std::unique_ptr<Entry[]> entries_;  // root first, then the inner children in slot order
    std::size_t entry_count_ = 0;
};

}  // namespace rebraid
