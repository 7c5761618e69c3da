#pragma once

#include <functional>
#include <vector>

#include "rebraid/bvh/build_prim.h"
#include "rebraid/bvh/build_settings.h"
#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/wide_bvh.h"
#include "rebraid/core/scene.h"

namespace rebraid {

/// Builds an ObjectBvh with the project's parallel binned-SAH builder; with spatial splits when
/// settings.spatial_split_budget > 0 (spatial_split_bvh_builder.h), a triangle then in each
/// leaf that holds a part of it.
ObjectBvh build_object_bvh(const Mesh& mesh, const BuildSettings& settings = {});

/// Completes an ObjectBvh from a tree whose leaves index `leaf_prims` (primIDs of `mesh` in
/// leaf order), e.g. one made by Embree's rtcBuildBVH: copies the triangles in leaf order,
/// and pre-arranges them per leaf when `pre_arranged_leaves` (BuildSettings).
ObjectBvh make_object_bvh(const Mesh& mesh, WideBvh tree, std::vector<PrimId> leaf_prims,
                          bool pre_arranged_leaves = true);

/// One BuildPrim per triangle of `mesh` (bounds in object space, id = primID).
std::vector<BuildPrim> make_triangle_build_prims(const Mesh& mesh);

/// How object BVHs are made: the project's builder (default) or, from embree_glue,
/// Embree's rtcBuildBVH. Must be callable from several threads at once.
using ObjectBvhBuilder = std::function<ObjectBvh(const Mesh&)>;

/// The project's binned-SAH builder with `settings` (by default those of BVHs built once, with
/// spatial splits).
ObjectBvhBuilder own_object_bvh_builder(
    const BuildSettings& settings = static_object_build_settings());

/// One ObjectBvh per mesh of `scene` (index = MeshId), built in parallel.
std::vector<ObjectBvh> build_object_bvhs(const Scene& scene, const ObjectBvhBuilder& builder);

}  // namespace rebraid
