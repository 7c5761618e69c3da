#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "rebraid/core/animated_object.h"
#include "rebraid/core/scene.h"
#include "rebraid/core/transform.h"
#include "rebraid/core/types.h"

namespace rebraid {

/// Where and how large the copies of an animated object go in a static scene.
struct DynamicPlacementSettings {
    /// Copies of the animated object; at least 1.
    std::size_t copy_count = 4;
    /// Largest extent of one copy (in its rest pose) over the largest extent of the static
    /// scene: in (0, 1].
    float size_fraction = 0.15f;
    /// Seed of the jitter of each copy's spot and of its turn about the vertical (Y) axis.
    std::uint64_t seed = 1;

    /// Throws rebraid::Error naming the field and value for an impossible setting.
    void validate() const;
};

/// A static scene with copies of an animated object in it (docs/updates.md): the
/// static meshes and instances first, unchanged, then per copy the object's meshes and
/// instances. The copies stand side by side across the middle of the static scene's bounds
/// along its longer horizontal axis, their bottom at the height of the bounds' centre, each
/// turned about Y and jittered by the seed, and each plays the animation shifted by
/// copy * duration / copy_count, so they are out of step.
///
/// pose() moves the dynamic part only: positions of dynamic_meshes() and transforms of
/// moving_instances(); everything else stays bit-identical from frame to frame.
class DynamicScene {
public:
    /// Throws rebraid::Error for invalid settings, an animated object without triangles or
    /// an invalid static scene. `object` must outlive this.
    DynamicScene(const Scene& static_scene, const AnimatedObject& object,
                 const DynamicPlacementSettings& settings = {});

    /// Poses every copy at `time` seconds (plus its shift). Not thread-safe.
    void pose(float time);

    /// The composed scene, posed at the last pose() (at time 0 after construction).
    const Scene& scene() const { return scene_; }
    /// Meshes whose positions pose() changes (ascending).
    const std::vector<MeshId>& dynamic_meshes() const { return dynamic_meshes_; }
    /// Instances whose transform pose() changes (ascending).
    const std::vector<InstanceId>& moving_instances() const { return moving_instances_; }
    /// Instances that reference a dynamic mesh or move: what a flat structure must rewrite.
    const std::vector<InstanceId>& changing_instances() const { return changing_instances_; }
    /// True for meshes in dynamic_meshes().
    bool is_dynamic_mesh(MeshId mesh_id) const { return is_dynamic_mesh_[mesh_id] != 0; }
    std::size_t static_mesh_count() const { return static_mesh_count_; }
    std::size_t static_instance_count() const { return static_instance_count_; }
    std::size_t copy_count() const { return copies_.size(); }
    /// Object space of the animated object -> world, for copy `copy_id`.
    const AffineTransform& placement(std::size_t copy_id) const {
        return copies_[copy_id].placement;
    }

private:
    struct Copy {
        Scene posed;  ///< the object's own scene, posed at this copy's time
        AffineTransform placement;
        float time_shift = 0.0f;
    };

    const AnimatedObject& object_;
    Scene scene_;
    std::vector<Copy> copies_;
    std::size_t static_mesh_count_ = 0, static_instance_count_ = 0;
    std::vector<MeshId> dynamic_meshes_;
    std::vector<InstanceId> moving_instances_, changing_instances_;
    std::vector<char> is_dynamic_mesh_;
};

}  // namespace rebraid
