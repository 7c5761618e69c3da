#include "rebraid/dynamic/frame_sah_cache.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <string>
#include <utility>

#include "rebraid/core/error.h"
#include "rebraid/top_level/bvh_stats.h"

namespace rebraid {

FrameSahCache::FrameSahCache(std::vector<char> is_fixed_instance)
    : is_fixed_(std::move(is_fixed_instance)),
      entries_(is_fixed_.size()),
      fixed_bounds_(is_fixed_.size()) {}

double FrameSahCache::scene_half_area(const TopLevelBvh& top,
                                      std::span<const ObjectBvh> object_bvhs,
                                      std::span<const std::uint32_t> instance_mesh,
                                      std::span<const AffineTransform> object_to_world) {
    // As instanced_scene_half_area(), with the boxes of fixed instances remembered (each
    // index written by one task only).
    return reached_instances_half_area(top, object_to_world.size(), [&](InstanceId id) {
        const bool is_fixed = id < is_fixed_.size() && is_fixed_[id];
        if (is_fixed && fixed_bounds_[id]) return *fixed_bounds_[id];
        const BBox3f box = instance_world_bounds(id, object_bvhs, instance_mesh, object_to_world);
        if (is_fixed) fixed_bounds_[id] = box;
        return box;
    });
}

std::optional<double> FrameSahCache::find(InstanceId instance_id, NodeRef node,
                                          float entry_area) const {
    if (instance_id >= is_fixed_.size() || !is_fixed_[instance_id]) return std::nullopt;
    const std::vector<Entry>& entries = entries_[instance_id];
    auto it = std::lower_bound(
        entries.begin(), entries.end(), node.bits(),
        [](const Entry& entry, std::uint32_t bits) { return entry.node_bits < bits; });
    // Several entries may share a node when its item's box changed (another build setting).
    for (; it != entries.end() && it->node_bits == node.bits(); ++it)
        if (it->entry_area == entry_area) return it->cost;
    return std::nullopt;
}

std::size_t FrameSahCache::remembered_count() const {
    std::size_t count = 0;
    for (const std::vector<Entry>& entries : entries_) count += entries.size();
    return count;
}

double FrameSahCache::sah(const TopLevelBvh& top, std::span<const ObjectBvh> object_bvhs,
                          std::span<const std::uint32_t> instance_mesh,
                          std::span<const AffineTransform> object_to_world) {
    if (top.item_bounds.size() != top.items.size())
        throw Error("FrameSahCache::sah: " + std::to_string(top.item_bounds.size()) +
                    " item boxes for " + std::to_string(top.items.size()) + " items");
    last_computed_count_ = 0;
    const double scene_area = scene_half_area(top, object_bvhs, instance_mesh, object_to_world);
    if (scene_area <= 0.0) return 0.0;
    // Items in parallel, reading the cache only; what was computed is remembered afterwards,
    // in item order, so the cache's content does not depend on the thread count.
    std::vector<double> item_costs(top.items.size());
    std::vector<char> is_computed(top.items.size(), 0);
    tbb::parallel_for(std::size_t(0), top.items.size(), [&](std::size_t i) {
        const TopLevelItem& item = top.items[i];
        const float entry_area = top.item_bounds[i].half_area();
        if (const std::optional<double> known =
                find(item.instance_id, item.object_node, entry_area)) {
            item_costs[i] = *known;
            return;
        }
        item_costs[i] =
            object_subtree_cost(object_bvhs[instance_mesh[item.instance_id]], item.object_node,
                                top.item_bounds[i], object_to_world[item.instance_id]);
        is_computed[i] = 1;
    });
    std::vector<InstanceId> touched;
    for (std::size_t i = 0; i < top.items.size(); ++i) {
        if (!is_computed[i]) continue;
        ++last_computed_count_;
        const TopLevelItem& item = top.items[i];
        if (item.instance_id >= is_fixed_.size() || !is_fixed_[item.instance_id]) continue;
        std::vector<Entry>& entries = entries_[item.instance_id];
        if (touched.empty() || touched.back() != item.instance_id)
            touched.push_back(item.instance_id);
        entries.push_back({item.object_node.bits(), top.item_bounds[i].half_area(), item_costs[i]});
    }
    // Sorted once per instance (not per insertion: a first frame adds thousands to one
    // instance of a world-space scene); an item twice in one top is remembered once.
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    for (InstanceId id : touched) {
        std::vector<Entry>& entries = entries_[id];
        std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
            return a.node_bits != b.node_bits ? a.node_bits < b.node_bits
                                              : a.entry_area < b.entry_area;
        });
        entries.erase(std::unique(entries.begin(), entries.end(),
                                  [](const Entry& a, const Entry& b) {
                                      return a.node_bits == b.node_bits &&
                                             a.entry_area == b.entry_area;
                                  }),
                      entries.end());
    }
    double cost = top_inner_cost(top);
    for (double c : item_costs) cost += c;
    return cost / scene_area;
}

}  // namespace rebraid
