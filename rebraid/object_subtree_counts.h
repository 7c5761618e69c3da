#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "rebraid/object_bvh.h"
#include "rebraid/scene.h"

namespace rebraid {

/// Triangles below each inner node of `bvh` (index = node id; leaf references below count
/// their triangles, so with spatial splits a triangle counts once per leaf holding it). One
/// pass over the nodes. Computed by the re-braiding builder at the start of each build, so it
/// is never stale after an object BVH is refitted or restructured.
std::vector<std::uint32_t> subtree_prim_counts(const ObjectBvh& bvh);

/// subtree_prim_counts for every mesh that `instances` of `scene` use; empty vectors for the
/// others (their BVHs are never opened). Meshes in parallel.
std::vector<std::vector<std::uint32_t>> subtree_prim_counts(const Scene& scene,
                                                            std::span<const ObjectBvh> object_bvhs,
                                                            std::span<const InstanceId> instances);

}  // namespace rebraid
