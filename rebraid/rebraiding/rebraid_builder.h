#pragma once

#include <cstdint>
#include <span>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/core/scene.h"
#include "rebraid/rebraiding/rebraid_settings.h"
#include "rebraid/top_level/top_level_bvh.h"

namespace rebraid {

/// A re-braided top level and what its build did.
struct RebraidBuild {
    TopLevelBvh top;
    std::uint64_t brefs = 0;   ///< BRefs left after opening (= top-level items)
    std::uint64_t budget = 0;  ///< extra BRef slots the build was allowed (§5.2)
    std::uint64_t opened = 0;  ///< BRefs opened
};

/// The re-braiding top-level builder (Benthin, Woop, Wald, Áfra, HPG 2017): a top-down
/// binned-SAH build over BRefs that opens large BRefs into their object-BVH children while it
/// partitions (§4.1), keeping all BRefs in one pre-allocated array of budgeted segments
/// (§5.2). Where anything opened, the tree is then built again over the final BRefs
/// (RebraidSettings::rebuild_tree). The result is traversed exactly like a plain two-level top
/// (§5.5); the tree is the same for any thread count. One BRef per instance to start with, at its
/// object root with the root's primitive count; instances of empty meshes are left out.
RebraidBuild build_rebraid(const Scene& scene, std::span<const ObjectBvh> object_bvhs,
                           const RebraidSettings& settings = {});

/// The same over a subset of the scene's instances, given by id in the order their BRefs
/// start in (the items keep the scene's instance ids). The budget counts only these
/// instances. Throws rebraid::Error for an id past the scene's instances.
RebraidBuild build_rebraid(const Scene& scene, std::span<const ObjectBvh> object_bvhs,
                           const RebraidSettings& settings, std::span<const InstanceId> instances);

}  // namespace rebraid
