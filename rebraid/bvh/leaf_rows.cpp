#include "rebraid/bvh/leaf_rows.h"

#include <bit>
#include <string>

#include "rebraid/core/error.h"
#include "rebraid/core/huge_pages.h"

namespace rebraid {
namespace {

/// Calls `visit(leaf)` for every leaf below `root`.
template <class Visit>
void for_each_leaf(const std::vector<WideNode>& nodes, NodeRef root, Visit&& visit) {
    if (root.is_empty()) return;
    std::vector<NodeRef> pending{root};
    while (!pending.empty()) {
        const NodeRef ref = pending.back();
        pending.pop_back();
        if (ref.is_leaf()) {
            visit(ref);
            continue;
        }
        for (const NodeRef child : nodes[ref.node_id()].children)
            if (!child.is_empty()) pending.push_back(child);
    }
}

}  // namespace

void write_leaf_rows(NodeRef leaf, const TriangleVerts* triangles, const PrimId* prim_ids,
                     float* rows) {
    const std::uint32_t first = leaf.first_prim(), count = leaf.prim_count();
    float* out = rows + kLeafRowPadding + std::size_t(kRowFloatsPerTriangle) * first;
    for (std::uint32_t i = 0; i < count; ++i) {
        const TriangleVerts& t = triangles[first + i];
        const Vec3f corners[3] = {t.v0, t.v1, t.v2};
        for (int c = 0; c < 3; ++c)
            for (int a = 0; a < 3; ++a) out[(3 * c + a) * count + i] = corners[c][a];
        out[kCornerRows * count + i] = std::bit_cast<float>(prim_ids[first + i]);
    }
}

void rewrite_leaf_rows(const std::vector<WideNode>& nodes, NodeRef root,
                       const std::vector<TriangleVerts>& triangles,
                       const std::vector<PrimId>& prim_ids, std::vector<float>& rows) {
    if (rows.size() != kRowFloatsPerTriangle * triangles.size() + 2 * kLeafRowPadding ||
        prim_ids.size() != triangles.size())
        throw Error("rewrite_leaf_rows: " + std::to_string(rows.size()) + " floats and " +
                    std::to_string(prim_ids.size()) + " ids for " +
                    std::to_string(triangles.size()) + " triangles (internal error)");
    for_each_leaf(nodes, root, [&](NodeRef leaf) {
        write_leaf_rows(leaf, triangles.data(), prim_ids.data(), rows.data());
    });
}

void rewrite_leaf_row_ids(const std::vector<WideNode>& nodes, NodeRef root,
                          const std::vector<std::uint32_t>& ids, std::vector<float>& rows) {
    if (rows.size() != kRowFloatsPerTriangle * ids.size() + 2 * kLeafRowPadding)
        throw Error("rewrite_leaf_row_ids: " + std::to_string(rows.size()) + " floats for " +
                    std::to_string(ids.size()) + " ids (internal error)");
    for_each_leaf(nodes, root, [&](NodeRef leaf) {
        const std::uint32_t first = leaf.first_prim(), count = leaf.prim_count();
        float* id_row = rows.data() + kLeafRowPadding + std::size_t(kRowFloatsPerTriangle) * first +
                        kCornerRows * count;
        for (std::uint32_t i = 0; i < count; ++i) id_row[i] = std::bit_cast<float>(ids[first + i]);
    });
}

std::vector<float> make_leaf_rows(const std::vector<WideNode>& nodes, NodeRef root,
                                  const std::vector<TriangleVerts>& triangles,
                                  const std::vector<PrimId>& prim_ids) {
    // Zeros in the padding and in positions no leaf covers: loads past a leaf read finite
    // values into lanes that are masked off.
    // On huge pages when large, as the corners are: rays in random order touch rows all
    // over the array, and with 4 KB pages nearly every access would also miss the TLB.
    std::vector<float> rows;
    reserve_on_huge_pages(rows, kRowFloatsPerTriangle * triangles.size() + 2 * kLeafRowPadding);
    rows.resize(kRowFloatsPerTriangle * triangles.size() + 2 * kLeafRowPadding, 0.0f);
    rewrite_leaf_rows(nodes, root, triangles, prim_ids, rows);
    return rows;
}

}  // namespace rebraid
