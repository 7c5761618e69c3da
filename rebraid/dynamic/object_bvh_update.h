#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include "rebraid/bvh/build_settings.h"
#include "rebraid/bvh/object_bvh.h"
#include "rebraid/core/scene.h"
#include "rebraid/dynamic/bvh_rotations.h"
#include "rebraid/dynamic/object_bvh_refit.h"
#include "rebraid/dynamic/selective_restructuring.h"
#include "rebraid/dynamic/treelet_sampling.h"

namespace rebraid {

/// How the BVH of a deforming object follows its mesh from frame to frame.
enum class UpdateStrategy {
    rebuild,      ///< the project's binned-SAH builder, every frame
    refit,        ///< refit_object_bvh(): same tree, new boxes
    rotate,       ///< refit plus tree rotations in one pass (BvhRotator, Kopta et al. 2012)
    restructure,  ///< refit, then selective restructuring (SelectiveRestructurer, Yoon 2007)
    automatic,    ///< "auto": refit; repair past a first SAH factor, rebuild past a second
                  ///< (see ObjectBvhUpdateSettings::repair_sah_factor, rebuild_sah_factor)
    treelet,      ///< refit, then treelet sampling (TreeletSampler, Barbier and Paulin)
};

/// Every strategy, in the order tools list them (auto last).
inline constexpr UpdateStrategy kUpdateStrategies[] = {
    UpdateStrategy::rebuild,     UpdateStrategy::refit,   UpdateStrategy::rotate,
    UpdateStrategy::restructure, UpdateStrategy::treelet, UpdateStrategy::automatic};

/// The command-line name: "rebuild", "refit", "rotate", "restructure", "treelet" or "auto".
std::string_view update_strategy_name(UpdateStrategy strategy);
/// Inverse of update_strategy_name(); throws rebraid::Error listing the valid names.
UpdateStrategy parse_update_strategy(std::string_view name);

/// Parameters of ObjectBvhUpdater. Defaults are the values bench/bench_update.cpp uses.
struct ObjectBvhUpdateSettings {
    UpdateStrategy strategy = UpdateStrategy::automatic;
    /// auto: rebuild once the SAH exceeds this factor times the SAH right after the last
    /// rebuild. Traversal time follows the SAH, so between rebuilds the tree traces on
    /// average about half the factor's excess (15% at 1.3) slower than a fresh one: the
    /// quality rotations must keep. A rebuild costs about 7 refits (bench_update), so
    /// on an exploding mesh 1.3 rebuilds every few frames for well under the per-frame cost
    /// of always rebuilding; lower factors rebuild nearly every frame there, higher ones let
    /// traversal lose more than the rebuilds cost. Both factors are SAH ratios rather than
    /// measured times, so the tree depends on the input only: a rule on timings would make
    /// it depend on the machine's load and break the same-tree-on-any-thread-count promise.
    double rebuild_sah_factor = 1.3;
    /// auto: below this factor of the last rebuild's SAH, a refit alone is enough (most
    /// animations: skinning and rigid parts keep a refit tree within a few percent of a
    /// rebuild, and a repair pass would cost time for nothing); past it, each frame also
    /// runs auto_repair. 1 <= repair_sah_factor; at or above rebuild_sah_factor, never.
    double repair_sah_factor = 1.1;
    /// auto: the repair past repair_sah_factor: refit (none), treelet, restructure or rotate
    /// (in RotationLeafMode::pre_split it needs a tree of one triangle per leaf, see `build`,
    /// which traces slower from the start). None by default: on both bench_update animations
    /// every repair cost more time than the rebuilds it saved and left the mean SAH where
    /// refit plus rebuilds has it (twist: refit-only auto 7.2 CPU ms/frame, 3 rebuilds, mean
    /// SAH 23.25; with treelet repairs 14.6 ms, 3 rebuilds, 23.27; explode: 36.2 ms, 21
    /// rebuilds, 33.29 against 37.1-42.8 ms and 33.2-33.9 with any repair). A mesh whose refit
    /// SAH creeps up slowly and whose rebuild is costly is where a repair can pay.
    UpdateStrategy auto_repair = UpdateStrategy::refit;
    /// restructure: refit plus rotations (true) or refit only (false) before restructuring.
    /// Rotations repair local damage every frame, restructuring the subtrees they cannot
    /// (the combination Kopta et al. suggest in their conclusion).
    bool restructure_rotates = false;
    /// Builder settings of every rebuild. With rotations in pre_split mode (strategy rotate,
    /// auto with auto_repair rotate, restructure with restructure_rotates), rebuilds use
    /// max_leaf_size = 1 instead.
    BuildSettings build;
    RefitSettings refit;
    RotationSettings rotation;
    RestructureSettings restructure;
    TreeletSettings treelet;

    /// Throws rebraid::Error naming the field and value when a setting is out of range.
    void validate() const;
};

/// What one update did.
struct ObjectBvhUpdateReport {
    /// What was applied: rebuild, refit, rotate, restructure or treelet (never automatic).
    /// auto reports rebuild on the frames it rebuilt (its refit or repair pass, when one ran
    /// first, counts in update_ms), its repair on frames it repaired, refit otherwise.
    UpdateStrategy applied = UpdateStrategy::refit;
    double update_ms = 0.0;         ///< wall time of the whole update
    double sah = 0.0;               ///< SAH of the updated tree (as object_bvh_sah())
    double sah_over_rebuild = 0.0;  ///< sah over the SAH right after the last rebuild
    RotationPassStats rotation;     ///< when rotations ran
    RestructureStats restructure;   ///< when restructuring ran
    TreeletStats treelet;           ///< when treelet sampling ran
};

/// Keeps one deforming object's BVH up to date with one strategy. One updater per object:
/// it keeps that object's state (the SAH after its last rebuild, the rotations' and the
/// restructuring's scratch). The first update takes the BVH it is given as the last rebuild
/// (its SAH before the update is the reference auto compares against).
class ObjectBvhUpdater {
public:
    /// Throws rebraid::Error on invalid settings.
    explicit ObjectBvhUpdater(const ObjectBvhUpdateSettings& settings = {});

    /// Brings `bvh` (built for `mesh`, whose positions have changed since) up to date with
    /// `mesh` by the strategy. Throws rebraid::Error when the mesh has another triangle count.
    ObjectBvhUpdateReport update(const Mesh& mesh, ObjectBvh& bvh);

    const ObjectBvhUpdateSettings& settings() const { return settings_; }
    /// The builder settings rebuilds use (see ObjectBvhUpdateSettings::build).
    BuildSettings rebuild_settings() const;

private:
    bool uses_pre_split() const;
    /// Rebuilds `bvh` and records its SAH as the new reference.
    double rebuild(const Mesh& mesh, ObjectBvh& bvh);
    /// Applies `strategy` (not automatic or rebuild) to `bvh`, filling `report`.
    void apply(UpdateStrategy strategy, const Mesh& mesh, ObjectBvh& bvh,
               ObjectBvhUpdateReport& report);

    ObjectBvhUpdateSettings settings_;
    std::optional<double> rebuild_sah_;              ///< SAH right after the last rebuild
    std::optional<double> last_sah_, previous_sah_;  ///< SAH after the last two updates
    BvhRotator rotator_;
    SelectiveRestructurer restructurer_;
    TreeletSampler treelet_sampler_;
};

}  // namespace rebraid
