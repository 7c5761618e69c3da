#include "rebraid/bvh/object_bvh_builder.h"

#include <tbb/parallel_for.h>

#include "rebraid/bvh/object_subtree_counts.h"
#include "rebraid/bvh/spatial_split_bvh_builder.h"
#include "rebraid/bvh/wide_bvh_builder.h"
#include "rebraid/core/build_timer.h"
#include "rebraid/core/huge_pages.h"

namespace rebraid {
namespace {

/// `vector` itself, or a copy on huge pages when it is large enough to profit (huge_pages.h).
template <class T>
std::vector<T> on_huge_pages_if_large(std::vector<T>&& vector) {
    if (vector.size() * sizeof(T) < kHugePageMinBytes) return std::move(vector);
    return copy_on_huge_pages(std::span<const T>(vector));
}

}  // namespace

std::vector<BuildPrim> make_triangle_build_prims(const Mesh& mesh) {
    std::vector<BuildPrim> prims(mesh.triangles.size());
    tbb::parallel_for(std::size_t(0), prims.size(), [&](std::size_t i) {
        BBox3f box;
        for (Vec3f corner : mesh.corners(PrimId(i))) box.extend(corner);
        prims[i] = {box, std::uint32_t(i), 1};
    });
    return prims;
}

ObjectBvh make_object_bvh(const Mesh& mesh, WideBvh tree, std::vector<PrimId> leaf_prims,
                          bool pre_arranged_leaves) {
    ObjectBvh bvh;
    bvh.nodes = on_huge_pages_if_large(std::move(tree.nodes));
    bvh.root = tree.root;
    bvh.bounds = tree.bounds;
    bvh.prim_ids = on_huge_pages_if_large(std::move(leaf_prims));
    reserve_on_huge_pages(bvh.triangles, bvh.prim_ids.size());
    bvh.triangles.resize(bvh.prim_ids.size());
    tbb::parallel_for(std::size_t(0), bvh.prim_ids.size(), [&](std::size_t i) {
        const auto corners = mesh.corners(bvh.prim_ids[i]);
        bvh.triangles[i] = {corners[0], corners[1], corners[2]};
    });
    if (pre_arranged_leaves)
        bvh.leaf_rows = make_leaf_rows(bvh.nodes, bvh.root, bvh.triangles, bvh.prim_ids);
    bvh.refresh_leaf_row_hints();
    bvh.node_prim_counts = subtree_prim_counts(bvh);
    return bvh;
}

ObjectBvh build_object_bvh(const Mesh& mesh, const BuildSettings& settings) {
    const BuildTimer timer;
    WideBvh tree;
    std::vector<PrimId> leaf_prims;
    if (settings.spatial_split_budget > 0.0f) {
        SpatialSplitBvh built = build_spatial_split_bvh(mesh, settings);
        tree = std::move(built.tree);
        leaf_prims = std::move(built.leaf_prims);
    } else {
        std::vector<BuildPrim> prims = make_triangle_build_prims(mesh);
        tree = build_wide_bvh(prims, settings);
        leaf_prims.resize(prims.size());
        for (std::size_t i = 0; i < prims.size(); ++i) leaf_prims[i] = prims[i].id;
    }
    ObjectBvh bvh =
        make_object_bvh(mesh, std::move(tree), std::move(leaf_prims), settings.pre_arranged_leaves);
    bvh.build_ms = timer.elapsed_ms();
    return bvh;
}

ObjectBvhBuilder own_object_bvh_builder(const BuildSettings& settings) {
    settings.validate();
    return [settings](const Mesh& mesh) { return build_object_bvh(mesh, settings); };
}

std::vector<ObjectBvh> build_object_bvhs(const Scene& scene, const ObjectBvhBuilder& builder) {
    std::vector<ObjectBvh> bvhs(scene.meshes.size());
    // One task per mesh; each build parallelises internally when its mesh is large.
    tbb::parallel_for(std::size_t(0), scene.meshes.size(), std::size_t(1),
                      [&](std::size_t m) { bvhs[m] = builder(scene.meshes[m]); });
    return bvhs;
}

}  // namespace rebraid
