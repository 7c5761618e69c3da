#include "rebraid/rebraiding/top_tree_rebuild.h"

#include <string>
#include <vector>

#include "rebraid/bvh/build_prim.h"
#include "rebraid/bvh/wide_bvh_builder.h"
#include "rebraid/core/error.h"
#include "rebraid/core/huge_pages.h"

namespace rebraid {

void rebuild_top_tree(TopLevelBvh& top, std::span<const std::uint32_t> item_weights,
                      const BuildSettings& settings) {
    const std::size_t n = top.items.size();
    if (item_weights.size() != n || top.item_bounds.size() != n)
        throw Error("rebuild_top_tree: " + std::to_string(item_weights.size()) + " weights and " +
                    std::to_string(top.item_bounds.size()) + " boxes for " + std::to_string(n) +
                    " items");
    if (n < 2) return;  // a leaf or nothing: no tree to choose
    std::vector<BuildPrim> prims(n);
    for (std::size_t i = 0; i < n; ++i)
        prims[i] = {top.item_bounds[i], std::uint32_t(i), item_weights[i]};
    WideBvh tree = build_wide_bvh(prims, settings);
    // build_wide_bvh left `prims` in leaf order: item i moves to where its prim went.
    std::vector<TopLevelItem> items;
    std::vector<BBox3f> bounds;
    reserve_on_huge_pages(items, n);
    reserve_on_huge_pages(bounds, n);
    items.resize(n);
    bounds.resize(n);
    for (std::size_t position = 0; position < n; ++position) {
        const std::uint32_t old = prims[position].id;
        items[position] = top.items[old];
        bounds[position] = top.item_bounds[old];
    }
    top.items = std::move(items);
    top.item_bounds = std::move(bounds);
    top.nodes = std::move(tree.nodes);
    top.root = tree.root;
    top.bounds.extend(tree.bounds);
}

}  // namespace rebraid
