#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/transform.h"
#include "rebraid/top_level/top_level_bvh.h"

namespace rebraid {

/// top_level_sah() of a structure rebuilt frame after frame over a scene whose instances
/// mostly stand still (DynamicSceneAccel). Nearly all of that SAH's time is the object
/// subtrees below the items, and an item of a fixed instance (one that neither moves nor
/// shows a mesh whose BVH changes) costs the same every frame: its cost is computed once and
/// remembered under (instance, object node, half area of its world box, the only part of the
/// box the cost reads), and so is its world box for the SAH's normaliser. Items of the other
/// instances, and
/// top-level nodes, are recomputed every frame. The result is bit-identical to
/// top_level_sah() on the same arguments (same per-item values, summed in the same order).
class FrameSahCache {
public:
    /// `is_fixed_instance[i]` (index = InstanceId) says whether instance i's items may be
    /// remembered. Precondition for every later sah(): the transforms and object BVHs of fixed
    /// instances are the ones of the first call.
    explicit FrameSahCache(std::vector<char> is_fixed_instance);

    /// The SAH of `top` over `object_bvhs`, as top_level_sah() with the same arguments.
    double sah(const TopLevelBvh& top, std::span<const ObjectBvh> object_bvhs,
               std::span<const std::uint32_t> instance_mesh,
               std::span<const AffineTransform> object_to_world);

    /// Items remembered so far (over all fixed instances).
    std::size_t remembered_count() const;
    /// Items whose cost the last sah() computed rather than remembered.
    std::size_t last_computed_count() const { return last_computed_count_; }

private:
    struct Entry {
        std::uint32_t node_bits;  ///< NodeRef::bits() of the item's object node
        float entry_area;         ///< half area of the item's world box
        double cost;              ///< object_subtree_cost() of the item
    };
    /// instanced_scene_half_area() with the world boxes of fixed instances remembered.
    double scene_half_area(const TopLevelBvh& top, std::span<const ObjectBvh> object_bvhs,
                           std::span<const std::uint32_t> instance_mesh,
                           std::span<const AffineTransform> object_to_world);
    /// The remembered cost of (instance, node, entry area), if any.
    std::optional<double> find(InstanceId instance_id, NodeRef node, float entry_area) const;

    std::vector<char> is_fixed_;
    std::vector<std::vector<Entry>> entries_;          ///< per instance, sorted by node_bits
    std::vector<std::optional<BBox3f>> fixed_bounds_;  ///< per instance, once computed
    std::size_t last_computed_count_ = 0;
};

}  // namespace rebraid
