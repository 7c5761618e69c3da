#pragma once

#include <cstdint>
#include <span>

#include "rebraid/bbox.h"
#include "rebraid/bref.h"
#include "rebraid/bref_bounds.h"
#include "rebraid/object_bvh.h"
#include "rebraid/transform.h"

namespace rebraid {

/// The object BVHs BRefs point into, and where each instance places its mesh.
struct BRefSource {
    std::span<const ObjectBvh> object_bvhs;          ///< index = MeshId
    std::span<const std::uint32_t> instance_mesh;    ///< index = InstanceId
    std::span<const AffineTransform> object_to_world;  ///< index = InstanceId
    BRefBoundsRule bounds_rule = BRefBoundsRule::transformed_box;

    const ObjectBvh& bvh_of(const BRefTarget& target) const {
        return object_bvhs[instance_mesh[target.instance_id]];
    }
};

/// Paper §4.2: in a segment, find the axis of largest extent of the segment's bounds; a BRef
/// is worth opening when it refers to an inner node (leaves cannot be opened) and its extent
/// along that axis exceeds `open_threshold` times the segment's.
struct OpeningCriterion {
    int axis = 0;
    float min_extent = 0.0f;

    OpeningCriterion(const BBox3f& segment_bounds, float open_threshold);
    bool wants_to_open(const BuildPrim& prim, const BRefTarget& target) const {
        return target.object_node.is_inner() && prim.bounds.extent()[axis] > min_extent;
    }
};

/// How many BRefs of `prims` meet `criterion` (§5.2 splits free space by these counts).
std::uint32_t count_openable(std::span<const BuildPrim> prims,
                             std::span<const BRefTarget> targets,
                             const OpeningCriterion& criterion, std::size_t parallel_threshold);

/// Paper §5.3: opens the BRefs of `segment` that meet `criterion`, in array order, while the
/// segment's free space lasts (a BRef opens iff the children wanted by it and all BRefs before
/// it fit, so serial and parallel runs open exactly the same ones). The first child replaces
/// the parent; its siblings are appended at the segment's end, each taking the next target
/// slot. A child's bounds are its object box mapped to world space (conservative AABB, §5.4);
/// its primitive count is the parent's divided by the number of children. Updates
/// `segment.end` and `segment.next_target`; returns how many BRefs were opened. Large
/// segments are processed in parallel blocks whose output slots come from prefix sums.
std::uint32_t open_brefs(BRefSegment& segment, std::span<BuildPrim> prims,
                         std::span<BRefTarget> targets, const OpeningCriterion& criterion,
                         const BRefSource& source, std::size_t parallel_threshold);

}  // namespace rebraid
