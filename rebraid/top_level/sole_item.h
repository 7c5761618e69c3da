#pragma once

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/types.h"
#include "rebraid/top_level/instance_target.h"

namespace rebraid {

/// A top level of one item (a scene of one instance that opening left whole), copied into one
/// record of the structure when its queries are chosen (InstancedAccel::sole_item(), read by
/// TraceKernels::sole_item_*): the item's instance target, its mesh's BVH arrays and its
/// object node side by side, so that a query reaches the object's first node one load after
/// the structure, where following top level, item, instance and mesh in turn put a chain of
/// dependent loads before every query's first node fetch.
struct SoleItem {
    /// The instance's target: its space and world-to-object map.
    InstanceTarget target;
    /// The arrays of the instance's mesh's object BVH.
    ObjectBvhView bvh;
    /// The item's object node, where queries start.
    NodeRef node;
    InstanceId instance = 0;
};

}  // namespace rebraid
