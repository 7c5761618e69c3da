#pragma once

#include <cstdint>

#include "embree_glue/reference/embree_device.h"
#include "embree_glue/reference/embree_reference.h"
#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/bvh/wide_bvh_builder.h"
#include "rebraid/core/scene.h"

namespace rebraid::glue {

/// Parameters of Builder 2: Embree's rtcBuildBVH producing the project's wide node layout.
/// The fields map one to one onto RTCBuildArguments. Defaults match the project's own
/// builder (8 wide, leaves of up to 4 triangles, unit costs) so the two can be compared.
struct EmbreeBvhBuilderSettings {
    /// low = Embree's Morton builder; medium = binned SAH; high = binned SAH that, with
    /// `can_split_triangles`, adds spatial splits. Without splits high builds exactly the
    /// medium tree (rtcBuildBVH falls back to the binned SAH builder).
    EmbreeBuildQuality quality = EmbreeBuildQuality::medium;
    /// Spatial splits at high quality (ignored otherwise): a triangle straddling a split
    /// plane is clipped and referenced from both sides, so ObjectBvh::prim_ids may hold a
    /// primID several times (in different leaves; each leaf box then bounds only the clipped
    /// part). Off by default: every triangle is then referenced exactly once.
    bool can_split_triangles = false;
    /// Children per inner node, 2..kBvhWidth.
    std::uint32_t max_branching_factor = kBvhWidth;
    /// Embree stops with "depth limit reached" beyond this many levels; 8 levels before it,
    /// it switches to splitting by index. 1..kMaxBvhDepth.
    std::uint32_t max_depth = kSahDepthLimit;
    /// The SAH counts leaf primitives in blocks of this many (a power of two, 1..16).
    std::uint32_t sah_block_size = 1;
    /// Ranges of at most this many triangles always become leaves (1..max_leaf_size).
    std::uint32_t min_leaf_size = 1;
    /// Leaves hold at most this many triangles (1..kMaxLeafSize).
    std::uint32_t max_leaf_size = 4;
    /// SAH cost of a node visit, relative to `intersection_cost`.
    float traversal_cost = 1.0f;
    /// SAH cost of one triangle test.
    float intersection_cost = 1.0f;

    /// Throws rebraid::Error naming the field and value when a setting is out of range.
    void validate() const;
};

/// Builds the BVH of `mesh` (object space) with Embree's rtcBuildBVH on `device`. Embree
/// grows a pointer tree through callbacks (thread-local allocation, primIDs recorded in the
/// leaves); it is then converted depth first into the WideNode array: node ids in pre-order,
/// children in Embree's order, primIDs inside a leaf sorted. The result does not depend on
/// thread timing. Safe to call from several threads at once on one device. Throws
/// rebraid::Error for invalid settings, a mesh beyond NodeRef's index range, or any Embree
/// error (e.g. the depth limit). build_ms covers everything but the device creation.
ObjectBvh build_object_bvh_embree(EmbreeDevice& device, const Mesh& mesh,
                                  const EmbreeBvhBuilderSettings& settings = {});

/// Same on a device of its own (creating an Embree device costs a few milliseconds: prefer
/// embree_object_bvh_builder() for many meshes).
ObjectBvh build_object_bvh_embree(const Mesh& mesh, const EmbreeBvhBuilderSettings& settings = {});

/// An ObjectBvhBuilder running build_object_bvh_embree with `settings` on one device shared
/// by every copy of the builder (created here). Validates `settings` first.
ObjectBvhBuilder embree_object_bvh_builder(const EmbreeBvhBuilderSettings& settings = {});

}  // namespace rebraid::glue
