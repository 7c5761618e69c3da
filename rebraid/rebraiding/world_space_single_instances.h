#pragma once

#include <optional>

#include "rebraid/core/scene.h"

namespace rebraid {

/// `scene` with each mesh that exactly one instance places, by a transform other than the
/// identity, moved into world space: its positions mapped by that transform and the instance
/// placed by the identity. Everything else is kept, ids included (instance i still places
/// mesh i's triangles, in the same order), so hits name the same instance and primitive.
/// A mesh placed once gains nothing from its own object space but cheap rigid motion, and
/// costs every ray that reaches it a mapped ray; built in world space it is the paper's
/// common case (§3.1: objects built in world space, instances only where they repeat), which
/// merge_world_space_items then traces without entering it. A mesh whose mapped positions
/// are not all finite keeps its object space. nullopt when no mesh moves.
std::optional<Scene> single_instances_in_world_space(const Scene& scene);

}  // namespace rebraid
