#pragma once

#include "rebraid/core/accel.h"
#include "rebraid/core/ray.h"
#include "rebraid/core/simd_level.h"
#include "rebraid/core/triangle_test.h"
#include "rebraid/top_level/located_hit.h"

namespace rebraid {

class FlatAccel;
class InstancedAccel;

/// The ray queries of the project's structures at one kernel level (simd_level.h) with one
/// triangle test (triangle_test.h). A
/// structure holds a pointer to one table and calls through it: one indirect call per ray
/// selects the instruction set.
struct TraceKernels {
    Hit (*flat_intersect)(const FlatAccel& accel, const Ray& ray, TraversalCounters* counters);
    bool (*flat_occluded)(const FlatAccel& accel, const Ray& ray);
    Hit (*instanced_intersect)(const InstancedAccel& accel, const Ray& ray,
                               TraversalCounters* counters);
    bool (*instanced_occluded)(const InstancedAccel& accel, const Ray& ray);
    LocatedHit (*instanced_intersect_located)(const InstancedAccel& accel, const Ray& ray,
                                              const CloserHitObserver* observer);
    /// The three instanced queries for a top level of one item (one instance left whole):
    /// the ray prepared once, in the item's space, and no top-level traversal.
    Hit (*sole_item_intersect)(const InstancedAccel& accel, const Ray& ray,
                               TraversalCounters* counters);
    bool (*sole_item_occluded)(const InstancedAccel& accel, const Ray& ray);
    LocatedHit (*sole_item_intersect_located)(const InstancedAccel& accel, const Ray& ray,
                                              const CloserHitObserver* observer);
    /// The three instanced queries for a top level with world-space items merged in
    /// (MergedTopLevel): one traversal through the top level and those items' object nodes.
    Hit (*merged_intersect)(const InstancedAccel& accel, const Ray& ray,
                            TraversalCounters* counters);
    bool (*merged_occluded)(const InstancedAccel& accel, const Ray& ray);
    LocatedHit (*merged_intersect_located)(const InstancedAccel& accel, const Ray& ray,
                                           const CloserHitObserver* observer);
    /// The same for a merged top level whose items are entered out of line
    /// (MergedTopLevel::enters_items_out_of_line).
    Hit (*merged_rare_items_intersect)(const InstancedAccel& accel, const Ray& ray,
                                       TraversalCounters* counters);
    bool (*merged_rare_items_occluded)(const InstancedAccel& accel, const Ray& ray);
    LocatedHit (*merged_rare_items_intersect_located)(const InstancedAccel& accel, const Ray& ray,
                                                      const CloserHitObserver* observer);
    /// The three instanced queries for a world tree (world_tree.h): one traversal whose
    /// leaves are tested in their instances' spaces, source by source.
    Hit (*world_tree_intersect)(const InstancedAccel& accel, const Ray& ray,
                                TraversalCounters* counters);
    bool (*world_tree_occluded)(const InstancedAccel& accel, const Ray& ray);
    LocatedHit (*world_tree_intersect_located)(const InstancedAccel& accel, const Ray& ray,
                                               const CloserHitObserver* observer);
};

/// The kernels of `level` with the triangle test `test`. Throws rebraid::Error when this build
/// or this CPU cannot run `level`.
const TraceKernels& trace_kernels(SimdLevel level, TriangleTest test);

}  // namespace rebraid
