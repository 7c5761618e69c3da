#pragma once

#include <cstdint>
#include <span>
#include <string_view>

#include "rebraid/core/scene.h"

namespace rebraid {

/// Families of generated scenes, modelled on the scenes of the paper (Benthin et al. 2017,
/// §6) to show when re-braiding pays off and when it must cost nothing. Every scene is Y-up
/// with objects standing on or above y = 0, and has exactly the requested number of
/// instances. Default instance counts keep a default scene (except `kHuge`) small enough for
/// a flat BVH over all its triangles to build in seconds on two cores.
enum class SceneKind {
    /// A forest: randomly turned (about Y, tilted by up to 7 degrees) and scaled (0.7-1.3)
    /// instances of four tree meshes (two branching broad-leaved trees, a conifer, a lumpy
    /// tree; 2-3k triangles each) whose canopies overlap heavily: the paper's Trees scene.
    /// Default 4,000 instances (about 10 M instanced triangles).
    kTrees,
    /// A crown: a jewelled band, fleurons on its rim, strings of pearls, beads and knots along
    /// arches meeting at an orb and cross; hundreds of small objects packed together, each
    /// overlapping its neighbours (the paper's Crown). Default 800 instances, objects in
    /// world space (see ObjectPlacement).
    kCrown,
    /// A plant's pipe work: long thin pipes, flanged pipes, I-beams and lattice trusses
    /// crossing each other through a volume, half axis-aligned, half in random directions
    /// (the paper's Powerplant: 56 objects). By default objects in world space, each made of
    /// kPowerplantPiecesPerObject pieces spread through the plant, so every object's box
    /// spans much of the plant; instanced (ObjectPlacement::instanced), one piece per
    /// instance. Default 56 (objects, or pieces when instanced).
    kPowerplant,
    /// A city: towers of varied stacked boxes, one per cell of a square grid, turned by
    /// multiples of 90 degrees and scaled, with streets between them, so no two instance
    /// boxes overlap: the case where re-braiding must cost nothing. Default 2,500 instances.
    kCity,
    /// The forest of kTrees with high-detail trees (12-16k triangles each): by default 12,000
    /// instances and about 170 M instanced triangles, which instancing keeps small in memory
    /// and on disk but a flat BVH over all triangles cannot afford (paper's Trees: 12,000
    /// instances, 522 M triangles).
    kHuge,
};

/// How generate_scene() places objects.
enum class ObjectPlacement {
    /// The kind's own choice: `world_space` for kCrown and kPowerplant, whose models in the
    /// paper are objects in world space (Benthin et al. 2017, §6: "56 objects", "850
    /// objects"); `instanced` for the others.
    kind_default,
    /// A few meshes, each placed many times by instance transforms.
    instanced,
    /// Every placement is a mesh of its own with world-space vertices and the identity
    /// transform (bake_instances_into_world_space()).
    world_space,
};

/// Parameters of generate_scene().
struct SceneGeneratorSettings {
    ObjectPlacement placement = ObjectPlacement::kind_default;
    /// Number of instances; 0 = the kind's default (default_instance_count()). At most
    /// kMaxGeneratedInstances.
    std::uint32_t instance_count = 0;
    /// Every random choice (placements and mesh shapes) comes from this seed.
    std::uint64_t seed = 1;
};

/// Pieces of pipe work per world-space Powerplant object.
inline constexpr std::uint32_t kPowerplantPiecesPerObject = 36;

/// Largest instance count generate_scene() accepts.
inline constexpr std::uint32_t kMaxGeneratedInstances = 50'000'000;

/// Every kind, in declaration order.
std::span<const SceneKind> all_scene_kinds();

/// Lower-case name of `kind` as the command line spells it ("trees", "crown", ...).
std::string_view scene_kind_name(SceneKind kind);

/// The kind called `name` (as scene_kind_name() spells it). Throws rebraid::Error listing
/// the valid names for anything else.
SceneKind parse_scene_kind(std::string_view name);

/// Instances generate_scene() makes for `kind` when settings.instance_count is 0.
std::uint32_t default_instance_count(SceneKind kind);

/// Generates a scene of the given family: deterministic for its settings (same settings,
/// same scene, bit for bit; another seed, another scene), with exactly
/// settings.instance_count instances (or the kind's default), and valid (Scene::validate()).
/// Throws rebraid::Error for an instance count above kMaxGeneratedInstances.
Scene generate_scene(SceneKind kind, const SceneGeneratorSettings& settings = {});

}  // namespace rebraid
