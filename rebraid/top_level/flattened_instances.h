#pragma once

#include <vector>

#include "rebraid/core/scene.h"
#include "rebraid/core/types.h"

namespace rebraid {

/// Every instance's triangles as one mesh, in instance order: what the flat BVH and a world
/// tree are built over.
struct FlattenedInstances {
    /// The corners as the instances place them.
    Mesh world;
    /// The same triangles and numbering with the meshes' own (object-space) corners; empty
    /// unless asked for.
    Mesh object;
    /// Per triangle of `world`: its instance, and its primID in that instance's mesh.
    std::vector<InstanceId> instance;
    std::vector<PrimId> prim;
};

/// Flattens `scene`'s instances; `keeps_object_space` also fills FlattenedInstances::object.
FlattenedInstances flatten_instances(const Scene& scene, bool keeps_object_space);

}  // namespace rebraid
