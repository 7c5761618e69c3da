#include "rebraid/bvh/object_support_tables.h"

namespace rebraid {

ObjectSupportTables::ObjectSupportTables(const ObjectBvh& bvh) : bvh_(&bvh) {
    if (bvh.root.is_empty()) return;
    std::size_t count = 1;
    const WideNode* root = bvh.root.is_inner() ? &bvh.nodes[bvh.root.node_id()] : nullptr;
    if (root)
        for (int c = 0; c < kBvhWidth && !root->children[c].is_empty(); ++c)
            count += root->children[c].is_inner() ? 1 : 0;
    entries_ = std::make_unique<Entry[]>(count);
    entry_count_ = count;
    entries_[0].node = bvh.root;
    entries_[0].box = bvh.bounds;
    std::size_t k = 1;
    if (root)
        for (int c = 0; c < kBvhWidth && !root->children[c].is_empty(); ++c)
            if (root->children[c].is_inner()) {
                entries_[k].node = root->children[c];
                entries_[k].box = root->child_bounds(c);
                ++k;
            }
    find(bvh.root);  // every instance asks for it
}

const SupportTable* ObjectSupportTables::find(NodeRef node) const {
    for (std::size_t k = 0; k < entry_count_; ++k) {
        const Entry& entry = entries_[k];
        if (!(entry.node == node)) continue;
        std::call_once(entry.made,
                       [&] { entry.table = SupportTable(*bvh_, entry.node, entry.box); });
        return &entry.table;
    }
    return nullptr;
}

}  // namespace rebraid
