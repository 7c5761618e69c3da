#include "rebraid/dynamic/incremental_top_level.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <string>
#include <utility>

#include "rebraid/bvh/object_subtree_counts.h"
#include "rebraid/bvh/wide_bvh_builder.h"
#include "rebraid/core/build_timer.h"
#include "rebraid/core/error.h"

namespace rebraid {

void IncrementalTopSettings::validate() const {
    if (max_cut_pieces < 1 || max_cut_pieces > NodeRef::kMaxFirst)
        throw Error("IncrementalTopSettings: max_cut_pieces " + std::to_string(max_cut_pieces) +
                    " must be in [1, " + std::to_string(NodeRef::kMaxFirst) + "]");
}

namespace {

/// The upper build's primitives: the cut's pieces (ids [0, pieces)), then the dynamic BRefs
/// (ids [pieces, pieces + dynamic items)), each weighted by the triangles below it, the
/// weight re-braiding bins by (paper §4.3).
std::vector<BuildPrim> make_upper_prims(const StaticTopCut& cut, const StaticTopSummary& summary,
                                        const TopLevelBvh& dynamic_top, const Scene& scene,
                                        std::span<const ObjectBvh> object_bvhs) {
    constexpr std::uint64_t kMaxWeight = std::numeric_limits<std::uint32_t>::max();
    auto weight = [&](std::uint64_t prims) {
        return std::uint32_t(std::clamp<std::uint64_t>(prims, 1, kMaxWeight));
    };
    std::vector<BuildPrim> prims;
    prims.reserve(cut.pieces.size() + dynamic_top.items.size());
    for (const StaticTopPiece& piece : cut.pieces)
        prims.push_back(
            {piece.bounds, std::uint32_t(prims.size()), weight(summary.prims_of(piece.ref))});
    // Dynamic BVHs change every frame: count their nodes afresh, once per mesh that has an
    // item below its root.
    const LazySubtreeCounts subtree_counts(object_bvhs);
    for (std::size_t i = 0; i < dynamic_top.items.size(); ++i) {
        const TopLevelItem& item = dynamic_top.items[i];
        const MeshId mesh_id = scene.instances[item.instance_id].mesh_id;
        prims.push_back({dynamic_top.item_bounds[i], std::uint32_t(prims.size()),
                         weight(subtree_counts.item_prim_count(mesh_id, item.object_node))});
    }
    return prims;
}

/// Deepest wide level a ray can reach once the upper tree's leaves point at the pieces.
std::uint32_t grafted_depth(const WideBvh& upper, NodeRef ref, std::uint32_t depth,
                            std::span<const BuildPrim> prims, const StaticTopCut& cut,
                            const StaticTopSummary& summary) {
    if (ref.is_empty()) return depth;
    if (ref.is_leaf()) {
        const std::uint32_t piece = prims[ref.first_prim()].id;
        return depth + (piece < cut.pieces.size() ? summary.height_of(cut.pieces[piece].ref) : 0);
    }
    std::uint32_t deepest = depth + 1;
    for (NodeRef child : upper.nodes[ref.node_id()].children)
        deepest = std::max(deepest, grafted_depth(upper, child, depth + 1, prims, cut, summary));
    return deepest;
}

/// The settings of the static build: the budget scaled from the static instances to the whole
/// scene (IncrementalTopSettings::static_budget_for_whole_scene), within the settings' ranges.
RebraidSettings whole_scene_budget(RebraidSettings settings, const Scene& scene,
                                   std::span<const ObjectBvh> object_bvhs,
                                   std::span<const InstanceId> static_instances) {
    auto count = [&](InstanceId id) -> std::pair<std::uint64_t, std::uint64_t> {
        const std::uint32_t prims = object_bvhs[scene.instances[id].mesh_id].prim_count();
        return {prims > 0 ? 1 : 0, prims};
    };
    std::uint64_t static_instances_count = 0, static_prims = 0, all_instances = 0, all_prims = 0;
    for (InstanceId id : static_instances) {
        if (id >= scene.instances.size()) return settings;  // build_rebraid reports it
        const auto [instances, prims] = count(id);
        static_instances_count += instances;
        static_prims += prims;
    }
    for (std::size_t id = 0; id < scene.instances.size(); ++id) {
        const auto [instances, prims] = count(InstanceId(id));
        all_instances += instances;
        all_prims += prims;
    }
    // Under BudgetRule::larger both scale, so whichever rule wins keeps its share.
    if (settings.budget_rule != BudgetRule::per_primitive && static_instances_count > 0)
        settings.budget_factor =
            float(std::min(1e6, double(settings.budget_factor) * double(all_instances) /
                                    double(static_instances_count)));
    if (settings.budget_rule != BudgetRule::per_instance && static_prims > 0)
        settings.primitives_per_bref = float(std::max(
            1.0, double(settings.primitives_per_bref) * double(static_prims) / double(all_prims)));
    return settings;
}

}  // namespace

IncrementalTopLevel::IncrementalTopLevel(const RebraidSettings& rebraid,
                                         const IncrementalTopSettings& settings)
    : rebraid_(rebraid), settings_(settings) {
    rebraid_.validate();
    settings_.validate();
}

void IncrementalTopLevel::build_static(const Scene& scene, std::span<const ObjectBvh> object_bvhs,
                                       std::span<const InstanceId> static_instances) {
    const BuildTimer timer;
    if (object_bvhs.size() != scene.meshes.size())
        throw Error("IncrementalTopLevel::build_static: " + std::to_string(object_bvhs.size()) +
                    " object BVHs for " + std::to_string(scene.meshes.size()) + " meshes");
    const RebraidSettings static_settings =
        settings_.static_budget_for_whole_scene
            ? whole_scene_budget(rebraid_, scene, object_bvhs, static_instances)
            : rebraid_;
    static_ = build_rebraid(scene, object_bvhs, static_settings, static_instances);
    summary_ = summarize_static_top(static_.top, scene, object_bvhs);
    static_instances_.assign(static_instances.begin(), static_instances.end());
    is_static_.assign(scene.instances.size(), 0);
    for (InstanceId id : static_instances) is_static_[id] = 1;
    ++static_build_count_;
    static_build_ms_ = timer.elapsed_ms();
}

IncrementalTopBuild IncrementalTopLevel::build_frame(
    const Scene& scene, std::span<const ObjectBvh> object_bvhs,
    std::span<const InstanceId> dynamic_instances) const {
    return build_frame(scene, object_bvhs, dynamic_instances, TopLevelBvh{});
}

void IncrementalTopLevel::check_starts_with_static_top(const TopLevelBvh& top) const {
    const TopLevelBvh& fixed = static_.top;
    const auto fail = [](const std::string& what) {
        throw Error("IncrementalTopLevel::build_frame: the previous top " + what +
                    " (pass a top an earlier build_frame() made since build_static())");
    };
    if (top.nodes.size() < fixed.nodes.size() || top.items.size() < fixed.items.size() ||
        top.item_bounds.size() < fixed.items.size())
        fail("has " + std::to_string(top.nodes.size()) + " nodes and " +
             std::to_string(top.items.size()) + " items, fewer than the static top's " +
             std::to_string(fixed.nodes.size()) + " and " + std::to_string(fixed.items.size()));
    // A sample, not every byte: comparing all of it would cost what the reuse saves.
    constexpr std::size_t kSamples = 64;
    const auto same_node = [&](std::size_t i) {
        return std::memcmp(&top.nodes[i], &fixed.nodes[i], sizeof(WideNode)) == 0;
    };
    const auto same_item = [&](std::size_t i) {
        return top.items[i].instance_id == fixed.items[i].instance_id &&
               top.items[i].object_node == fixed.items[i].object_node &&
               top.item_bounds[i] == fixed.item_bounds[i];
    };
    for (std::size_t k = 0; k < kSamples && !fixed.nodes.empty(); ++k) {
        const std::size_t i = k * (fixed.nodes.size() - 1) / (kSamples - 1);
        if (!same_node(i)) fail("differs from the static top at node " + std::to_string(i));
    }
    for (std::size_t k = 0; k < kSamples && !fixed.items.empty(); ++k) {
        const std::size_t i = k * (fixed.items.size() - 1) / (kSamples - 1);
        if (!same_item(i)) fail("differs from the static top at item " + std::to_string(i));
    }
}

IncrementalTopBuild IncrementalTopLevel::build_frame(const Scene& scene,
                                                     std::span<const ObjectBvh> object_bvhs,
                                                     std::span<const InstanceId> dynamic_instances,
                                                     TopLevelBvh previous) const {
    const BuildTimer timer;
    if (static_build_count_ == 0)
        throw Error("IncrementalTopLevel::build_frame: build_static() has not run");
    if (object_bvhs.size() != scene.meshes.size())
        throw Error("IncrementalTopLevel::build_frame: " + std::to_string(object_bvhs.size()) +
                    " object BVHs for " + std::to_string(scene.meshes.size()) + " meshes");
    if (scene.instances.size() < is_static_.size())
        throw Error("IncrementalTopLevel::build_frame: the scene has " +
                    std::to_string(scene.instances.size()) +
                    " instances, the static top was built over a scene with " +
                    std::to_string(is_static_.size()));
    for (InstanceId id : dynamic_instances) {
        if (id >= scene.instances.size())
            throw Error("IncrementalTopLevel::build_frame: dynamic instance " + std::to_string(id) +
                        " of a scene with " + std::to_string(scene.instances.size()) +
                        " instances");
        if (id < is_static_.size() && is_static_[id])
            throw Error("IncrementalTopLevel::build_frame: instance " + std::to_string(id) +
                        " is both static and dynamic");
    }

    IncrementalTopBuild out;
    const RebraidBuild dynamic = build_rebraid(scene, object_bvhs, rebraid_, dynamic_instances);
    const StaticTopCut cut = cut_static_top(static_.top, dynamic.top, settings_.max_cut_pieces);
    std::vector<BuildPrim> prims = make_upper_prims(cut, summary_, dynamic.top, scene, object_bvhs);
    // One piece or BRef per leaf: a leaf reference to a piece is the piece's own reference.
    BuildSettings upper_settings = rebraid_.build;
    upper_settings.max_leaf_size = 1;
    const WideBvh upper = build_wide_bvh(prims, upper_settings);

    out.budget = static_.budget + dynamic.budget;
    out.opened = static_.opened + dynamic.opened;
    out.dynamic_brefs = dynamic.top.items.size();
    if (grafted_depth(upper, upper.root, 0, prims, cut, summary_) > std::uint32_t(kMaxBvhDepth)) {
        // The traversal stack holds kMaxBvhDepth levels: re-braid everything instead.
        std::vector<InstanceId> every(static_instances_);
        every.insert(every.end(), dynamic_instances.begin(), dynamic_instances.end());
        RebraidBuild full = build_rebraid(scene, object_bvhs, rebraid_, every);
        out.top = std::move(full.top);
        out.brefs = full.brefs;
        out.budget = full.budget;
        out.opened = full.opened;
        out.is_full_rebraid = true;
        out.top.build_ms = timer.elapsed_ms();
        return out;
    }

    // Graft: the static top's arrays first, unchanged, so kept subtrees keep their node and
    // item numbers; the upper nodes after them; dynamic BRefs appended in the order the upper
    // tree's nodes reach them.
    const TopLevelBvh& fixed = static_.top;
    const std::size_t item_count = fixed.items.size() + dynamic.top.items.size();
    if (item_count > NodeRef::kMaxFirst)
        throw Error("IncrementalTopLevel::build_frame: " + std::to_string(item_count) +
                    " items exceed the limit of " + std::to_string(NodeRef::kMaxFirst));
    TopLevelBvh& top = out.top;
    if (previous.nodes.empty() && previous.items.empty()) {
        top.nodes.reserve(fixed.nodes.size() + upper.nodes.size());
        top.nodes.assign(fixed.nodes.begin(), fixed.nodes.end());
        top.items.reserve(item_count);
        top.items.assign(fixed.items.begin(), fixed.items.end());
        top.item_bounds.reserve(item_count);
        top.item_bounds.assign(fixed.item_bounds.begin(), fixed.item_bounds.end());
    } else {
        check_starts_with_static_top(previous);
        top = std::move(previous);
    }
    top.nodes.resize(fixed.nodes.size());
    top.nodes.reserve(fixed.nodes.size() + upper.nodes.size());
    top.items.resize(fixed.items.size());
    top.items.reserve(item_count);
    top.item_bounds.resize(fixed.items.size());
    top.item_bounds.reserve(item_count);
    const auto node_offset = std::uint32_t(fixed.nodes.size());
    auto graft = [&](NodeRef ref) {
        if (ref.is_empty()) return ref;
        if (ref.is_inner()) return NodeRef::inner(ref.node_id() + node_offset);
        const std::uint32_t piece = prims[ref.first_prim()].id;
        if (piece < cut.pieces.size()) return cut.pieces[piece].ref;
        const std::size_t dynamic_item = piece - cut.pieces.size();
        top.items.push_back(dynamic.top.items[dynamic_item]);
        top.item_bounds.push_back(dynamic.top.item_bounds[dynamic_item]);
        return NodeRef::leaf(std::uint32_t(top.items.size() - 1), 1);
    };
    for (const WideNode& node : upper.nodes) {
        top.nodes.push_back(node);
        for (NodeRef& child : top.nodes.back().children) child = graft(child);
    }
    top.root = graft(upper.root);
    top.bounds = upper.bounds;
    top.has_partial_leaves = fixed.has_partial_leaves || dynamic.top.has_partial_leaves;

    out.brefs = top.items.size();
    out.cut_pieces = std::uint32_t(cut.pieces.size());
    out.opened_static_nodes = cut.opened_nodes;
    top.build_ms = timer.elapsed_ms();
    return out;
}

}  // namespace rebraid
