// Set-ups shared by the tests of object-BVH updates (object_bvh_update_test.cpp,
// treelet_sampling_test.cpp): a tree carried through the frames of a deforming mesh, and a
// tree degraded by refitting it to a shuffle of its triangles. The meshes themselves are
// object_bvh_checks.h's.
#pragma once

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/dynamic/object_bvh_refit.h"
#include "rebraid/top_level/bvh_stats.h"
#include "support/object_bvh_checks.h"

namespace rebraid::test {

/// Carries `bvh` (built on `rest`) through `frame_count` frames of the deforming rest mesh:
/// calls `update(mesh, bvh, frame)` for frame 1..frame_count with mesh = deformed(rest,
/// frame / frame_count), so the last frame is the full deformation. Returns the BVH after
/// the last frame.
template <class Update>
ObjectBvh update_through_frames(const Mesh& rest, int frame_count, ObjectBvh bvh, Update&& update) {
    for (int frame = 1; frame <= frame_count; ++frame)
        update(deformed(rest, float(frame) / float(frame_count)), bvh, frame);
    return bvh;
}

/// A tree built on the unwelded rest mesh and refit to a frame where its triangles moved
/// `blend` of the way to each other's places: the refit keeps the rest pose's grouping, so
/// its boxes span far-apart triangles (the case restructuring must repair).
struct DegradedTree {
    Mesh rest;           ///< the unwelded rest mesh the tree was built on
    Mesh mesh;           ///< the shuffled frame it was refit to
    ObjectBvh built;     ///< the tree as built on `rest`, before the refit
    ObjectBvh bvh;       ///< the refit tree
    double refit_sah;    ///< SAH of the refit tree
    double rebuilt_sah;  ///< SAH of a default build on `mesh`, what a repair aims for
};

/// The degraded tree of `rest_mesh()` with the tree built by `build`. Callers assert that
/// refit_sah is well above rebuilt_sah, as the repair tests need.
inline DegradedTree make_degraded_tree(const BuildSettings& build = {}, float blend = 0.5f) {
    DegradedTree degraded;
    degraded.rest = unwelded(rest_mesh());
    degraded.mesh = shuffled(degraded.rest, blend);
    degraded.built = build_object_bvh(degraded.rest, build);
    degraded.bvh = degraded.built;
    degraded.refit_sah = refit_object_bvh(degraded.mesh, degraded.bvh);
    degraded.rebuilt_sah = object_bvh_sah(build_object_bvh(degraded.mesh));
    return degraded;
}

}  // namespace rebraid::test
