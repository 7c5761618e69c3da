#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "rebraid/core/scene.h"
#include "rebraid/core/types.h"
#include "rebraid/io/gltf_scene.h"

namespace rebraid {

/// How GltfAnimator::apply() stores an instance that a pose hides (see GltfAnimator).
enum class GltfHiddenPose {
    /// As the loader stores a hidden instance: the identity transform and an empty Mesh
    /// (GltfAnimator::hidden_mesh()). The instance's MeshId changes while it is hidden: for
    /// a scene posed once and then built (`rebraid trace --time`, `rebraid render`).
    empty_mesh,
    /// A layout that never changes, as AnimatedObject requires: the instance has a Mesh of
    /// its own, listed in deformed_meshes(), whose vertices all move to one point while it
    /// is hidden (degenerate triangles are never hit), with the identity transform.
    collapsed_mesh,
};

/// Which glTF animation plays and how times outside it are treated.
struct GltfAnimationSettings {
    /// Index of the animation in the file's `animations`; -1 plays all of them at once (where
    /// two drive the same node property, the later animation in the file wins). A file without
    /// animations accepts 0 and -1 and never moves.
    int animation = 0;
    /// true: times outside [0, duration()] wrap into it (a looping clip); false: they clamp to
    /// the first / last key of each channel.
    bool loop = true;
    /// Vertices per parallel task when skinning and morphing; meshes with fewer vertices are
    /// posed serially. Has no effect on the result, only on speed.
    std::size_t parallel_grain = 4096;
    /// How a pose hides an instance (GltfHiddenPose).
    GltfHiddenPose hidden_pose = GltfHiddenPose::empty_mesh;
    /// Names the animated file in error messages (e.g. the path given to the loader); empty:
    /// messages name no file.
    std::string file_label{};

    /// Throws rebraid::Error naming the field and value for an impossible setting.
    void validate() const;
};

/// Evaluates a glTF animation at any time and poses a scene in place (docs/updates.md).
///
/// Node translation / rotation / scale channels (STEP, LINEAR, CUBICSPLINE) move instances
/// rigidly: their transforms are recomputed from the animated nodes down (in double, like the
/// loader). Skinned instances (nodes with a skin) and instances of meshes with morph targets
/// are *deforming*: their Mesh holds posed positions. Per the glTF specification a skinned
/// mesh is posed by its joints and the skinned node's own transform is ignored, so a skinned
/// instance gets the identity transform and its Mesh receives world-space positions.
///
/// Mesh layout: a deforming instance needs a Mesh of its own. The first deforming instance
/// of a glTF mesh keeps that Mesh unless a non-deforming instance uses it too; every other
/// deforming instance of it (a skinned or morphed mesh shared by several instances) uses a
/// copy appended to Scene::meshes, in instance order. prepare_scene() establishes that
/// layout; apply() does it itself the first time it sees a scene in the loader's layout (the
/// only time apply() allocates). mesh_ids()[i] is the Mesh of instance i in the prepared
/// layout; deformed_meshes() and moving_instances() refer to that layout. The loaded scene
/// holds skinned meshes in their object-space bind pose: apply() once before building
/// anything from a scene with skins or morph targets.
///
/// Hidden poses: an instance that is visible at rest but whose animated scale (of its node or
/// a node above it) makes its posed transform singular (|determinant| < 1e-30, as exporters
/// animate a scale to 0 to hide an object) is hidden in that pose, as the loader hides a
/// statically singular instance: it keeps its number and is never hit
/// (settings.hidden_pose says how). It shows again in poses where its transform is regular.
/// hideable_instances() lists the instances whose scale channels may reach such a pose (a
/// key of 0, a sign change, a spline that may dip to 0); only they ever hide. With
/// GltfHiddenPose::collapsed_mesh they count as deforming instances (a Mesh of their own, in
/// deformed_meshes()). An instance the loader hid stays hidden in every pose.
///
/// Skin weights are rescaled to sum 1 per vertex; a vertex with no weight at all follows the
/// skinned node's own world transform (its rest placement).
///
/// The animator copies what it needs from the model at construction (keyframes, skins, base
/// positions and morph deltas); it does not keep the GltfLoadResult.
class GltfAnimator {
public:
    /// `loaded` must come from load_gltf_scene_with_report() with keep_model = true. Throws
    /// rebraid::Error naming the file (settings.file_label), animation, channel / skin / mesh
    /// and problem for bad animation data: sampler inputs not strictly increasing, NaN keys,
    /// counts that do not match, missing nodes, samplers or accessors, joint indices past
    /// the skin, a node hierarchy that is not a forest.
    explicit GltfAnimator(const GltfLoadResult& loaded, const GltfAnimationSettings& settings = {});
    ~GltfAnimator();
    GltfAnimator(GltfAnimator&&) noexcept;
    GltfAnimator& operator=(GltfAnimator&&) noexcept;

    /// Seconds: the latest key time over the played animation's channels; 0 when the file has
    /// no animation.
    float duration() const;
    /// True when anything moves over time (a moving instance or a deformed mesh).
    bool animated() const;

    /// Brings `scene` (the loaded scene, or a copy of it) into the animator's layout: appends
    /// the Mesh copies of shared deforming meshes (and the hidden poses' empty Mesh) and
    /// points their instances at them. Does
    /// nothing when the scene is already in that layout. Throws rebraid::Error when `scene`
    /// does not come from the animated file (instance or mesh counts differ).
    void prepare_scene(Scene& scene) const;

    /// Poses `scene` at `time` seconds: transforms of moving instances, identity for skinned
    /// instances, positions of deforming meshes (morph targets, then skin), in place. Calls
    /// prepare_scene() first (which allocates only when the scene is in the loader's layout).
    /// Thread-safe for distinct scenes; large meshes are posed in parallel (TBB) with the
    /// same result on any thread count. Throws rebraid::Error for a non-finite `time` or a
    /// scene that does not come from the animated file.
    void apply(float time, Scene& scene) const;

    /// Meshes whose positions change over time (ascending, prepared layout).
    const std::vector<MeshId>& deformed_meshes() const;
    /// Instances whose transform changes over time (ascending). Skinned instances are never
    /// in it (their transform is the identity).
    const std::vector<InstanceId>& moving_instances() const;
    /// Mesh of every instance in the prepared layout (index = InstanceId); with
    /// GltfHiddenPose::empty_mesh, a hidden instance uses hidden_mesh() while it is hidden.
    const std::vector<MeshId>& mesh_ids() const;
    /// Moving instances that some pose may hide (ascending; see "Hidden poses").
    const std::vector<InstanceId>& hideable_instances() const;
    /// The empty Mesh of hidden instances in the prepared layout: the loader's, or with
    /// GltfHiddenPose::empty_mesh and hideable instances, one appended after the copies;
    /// kNoHiddenMesh when there is none.
    MeshId hidden_mesh() const;
    /// Number of meshes in the prepared layout (loaded meshes plus copies and, for hidden
    /// poses, an empty mesh).
    std::size_t mesh_count() const;

    struct Data;  ///< everything read from the file (defined in gltf_animation.cpp)

private:
    std::unique_ptr<const Data> data_;
};

}  // namespace rebraid
