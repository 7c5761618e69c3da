#include "rebraid/rebraiding/top_tree_rebuild.h"

#include <string>
#include <utility>
#include <vector>

#include "rebraid/core/error.h"
#include "rebraid/top_level/two_level_builder.h"

namespace rebraid {

void rebuild_top_tree(TopLevelBvh& top, std::span<const std::uint32_t> item_primitives,
                      const BuildSettings& settings) {
    const std::size_t n = top.items.size();
    if (item_primitives.size() != n || top.item_bounds.size() != n)
        throw Error("rebuild_top_tree: " + std::to_string(item_primitives.size()) +
                    " primitive counts and " + std::to_string(top.item_bounds.size()) +
                    " boxes for " + std::to_string(n) + " items");
    if (n < 2) return;  // a leaf or nothing: no tree to choose
    std::vector<std::uint32_t> weights(n);
    for (std::size_t i = 0; i < n; ++i) weights[i] = rebuilt_tree_weight(item_primitives[i]);
    // The plain top builder over the items as they are: the same split search and cut.
    TopLevelBvh rebuilt = build_top_level_over_items(std::move(top.items),
                                                     std::move(top.item_bounds), weights, settings);
    top.nodes = std::move(rebuilt.nodes);
    top.root = rebuilt.root;
    top.items = std::move(rebuilt.items);
    top.item_bounds = std::move(rebuilt.item_bounds);
    top.bounds.extend(rebuilt.bounds);
}

}  // namespace rebraid
