#pragma once

#include <optional>

#include "rebraid/core/scene.h"

namespace rebraid {

/// Which meshes meshes_in_world_space moves into world space (RebraidSettings).
struct WorldSpaceMeshSettings {
    /// Each mesh that exactly one instance places, by a transform other than the identity.
    bool single_instances = true;
    /// Also the meshes that several instances place, each instance given a world-space copy
    /// of its own, while the copies add at most this fraction of the scene's mesh triangles
    /// (the meshes whose copies add the fewest triangles first). 0: none.
    float copy_budget = 0.0f;
};

/// `scene` with meshes moved into world space as `settings` asks: a moved mesh's positions
/// mapped by its instance's transform, and that instance placed by the identity; a copied
/// mesh's first instance takes its place, the others get copies of it appended to the meshes.
/// Instance ids and each instance's triangles (their order in its mesh) do not change, so
/// hits name the same instance and primitive. A mesh placed once gains nothing from its own
/// object space but cheap rigid motion, and costs every ray that reaches it a mapped ray;
/// built in world space it is the paper's common case (§3.1: objects built in world space,
/// instances where objects repeat), which merge_world_space_items then traces without
/// entering it. A mesh whose mapped positions are not all finite keeps its object space.
/// nullopt when no mesh moves.
std::optional<Scene> meshes_in_world_space(const Scene& scene,
                                           const WorldSpaceMeshSettings& settings);

}  // namespace rebraid
