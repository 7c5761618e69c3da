#include "rebraid/dynamic/object_bvh_refit.h"

#include <tbb/parallel_for.h>

#include <string>

#include "rebraid/core/error.h"

namespace rebraid {
namespace {

/// Refits the subtree at `ref` (an inner node or a leaf) and returns its box and cost.
/// Children of nodes above `parallel_depth` run as parallel tasks; their results are
/// combined in slot order, so sums do not depend on which task finished first.
SubtreeRefit refit_subtree(const Mesh& mesh, ObjectBvh& bvh, NodeRef ref, int depth,
                           int parallel_depth) {
    if (ref.is_leaf()) {
        const BBox3f box = refit_leaf(mesh, bvh, ref);
        return {box, double(box.half_area()) * ref.prim_count()};
    }
    WideNode& node = bvh.nodes[ref.node_id()];
    const int child_count = node.child_count();
    SubtreeRefit children[kBvhWidth];
    const auto refit_child = [&](int slot) {
        children[slot] = refit_subtree(mesh, bvh, node.children[slot], depth + 1, parallel_depth);
    };
    if (depth < parallel_depth) {
        tbb::parallel_for(0, child_count, refit_child);
    } else {
        for (int slot = 0; slot < child_count; ++slot) refit_child(slot);
    }
    SubtreeRefit result;
    for (int slot = 0; slot < child_count; ++slot) {
        node.set_child(slot, node.children[slot], children[slot].bounds);
        result.bounds.extend(children[slot].bounds);
        result.cost += children[slot].cost;
    }
    result.cost += result.bounds.half_area();
    return result;
}

}  // namespace

void check_mesh_matches(const Mesh& mesh, const ObjectBvh& bvh, const char* caller) {
    if (mesh.triangles.size() != bvh.prim_ids.size() || bvh.triangles.size() != bvh.prim_ids.size())
        throw Error(std::string(caller) + ": mesh '" + mesh.name + "' has " +
                    std::to_string(mesh.triangles.size()) + " triangles, its BVH " +
                    std::to_string(bvh.prim_ids.size()) +
                    " (an update needs the mesh the BVH was built for)");
}

BBox3f refit_leaf(const Mesh& mesh, ObjectBvh& bvh, NodeRef leaf) {
    BBox3f box;
    const std::uint32_t end = leaf.first_prim() + leaf.prim_count();
    for (std::uint32_t i = leaf.first_prim(); i < end; ++i) {
        const auto corners = mesh.corners(bvh.prim_ids[i]);
        bvh.triangles[i] = {corners[0], corners[1], corners[2]};
        for (const Vec3f& corner : corners) box.extend(corner);
    }
    if (!bvh.leaf_rows.empty())
        write_leaf_rows(leaf, bvh.triangles.data(), bvh.prim_ids.data(), bvh.leaf_rows.data());
    return box;
}

double refit_object_bvh(const Mesh& mesh, ObjectBvh& bvh, const RefitSettings& settings) {
    check_mesh_matches(mesh, bvh, "refit_object_bvh");
    if (bvh.root.is_empty()) return 0.0;
    const SubtreeRefit root = refit_subtree(mesh, bvh, bvh.root, 0, settings.parallel_depth);
    bvh.bounds = root.bounds;
    const double root_area = root.bounds.half_area();
    return root_area > 0.0 ? root.cost / root_area : 0.0;
}

}  // namespace rebraid
