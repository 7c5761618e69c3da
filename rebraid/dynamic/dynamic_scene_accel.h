#pragma once

#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include "rebraid/bvh/build_settings.h"
#include "rebraid/bvh/object_bvh_builder.h"
#include "rebraid/dynamic/dynamic_scene.h"
#include "rebraid/dynamic/frame_sah_cache.h"
#include "rebraid/dynamic/incremental_top_level.h"
#include "rebraid/dynamic/object_bvh_update.h"
#include "rebraid/rebraiding/rebraid_settings.h"
#include "rebraid/top_level/instanced_accel.h"
#include "rebraid/top_level/two_level_builder.h"

namespace rebraid {

/// Which top level a DynamicSceneAccel rebuilds every frame.
enum class DynamicTop {
    two_level,  ///< "twolevel": one top-level leaf per instance (two_level_builder.h)
    rebraid,    ///< "rebraid": the re-braided top (rebraid_builder.h)
    /// "rebraid-incremental": the static instances' re-braided top built once, each frame
    /// only the dynamic part re-braided and grafted on (incremental_top_level.h)
    rebraid_incremental,
};

/// The command-line name: "twolevel", "rebraid" or "rebraid-incremental".
std::string_view dynamic_top_name(DynamicTop top);
/// Inverse of dynamic_top_name(); throws rebraid::Error listing the valid names.
DynamicTop parse_dynamic_top(std::string_view name);

/// Parameters of DynamicSceneAccel.
struct DynamicSceneAccelSettings {
    /// The incremental top by default: on scenes where most instances stand still it costs
    /// about what the plain top costs per frame and traces like the full re-braid
    /// (bench/RESULTS.md, frames); with no static instance it re-braids every frame in full.
    DynamicTop top = DynamicTop::rebraid_incremental;
    /// How the BVHs of deforming meshes follow them (one updater per dynamic mesh).
    ObjectBvhUpdateSettings update;
    /// Builder of the static meshes' BVHs (built once: with spatial splits).
    BuildSettings static_build = static_object_build_settings();
    /// When set, builds the static meshes' BVHs instead of the project's builder with
    /// static_build: they are built once, so a slower builder of better trees (Embree's with
    /// spatial splits, embree_glue/reference/embree_bvh_builder.h) pays for itself over the frames.
    /// Its trees are never refit, so they may hold a triangle in several leaves.
    ObjectBvhBuilder static_builder;
    /// The plain top (top = two_level).
    BuildSettings two_level_top = default_top_level_settings();
    /// The re-braided top (top = rebraid; top = rebraid_incremental for both its parts).
    /// Without the budget search: its doublings are whole top builds, and here they would be
    /// paid every frame (brainstem in cg57_cruiser, `rebraid animate`: two doublings took the
    /// re-braided top from 4.4 to 18 ms per frame and saved 5 ms of rendering).
    RebraidSettings rebraid{.budget_doublings = 0};
    /// The incremental top's cut (top = rebraid_incremental).
    IncrementalTopSettings incremental;
};

/// What one frame's update cost and gave.
struct DynamicFrameReport {
    double update_ms = 0.0;  ///< all dynamic object BVHs brought up to date
    double top_ms = 0.0;     ///< the top level rebuilt and the structure assembled
    /// SAH of the whole structure (docs/design.md, "SAH"; top_level_sah(), with the costs of static
    /// instances' items remembered from earlier frames: FrameSahCache). Not part of either time.
    double sah = 0.0;
};

/// A two-level structure over a DynamicScene that follows its animation: static object BVHs
/// built once, dynamic ones updated by an ObjectBvhUpdater each, the top level rebuilt from
/// scratch every frame over the same object BVHs (paper §6: the top is cheap to rebuild, so
/// re-braiding every frame is affordable). With top = rebraid_incremental, instances that
/// neither move nor reference a deforming mesh form a static top built once, and each frame
/// rebuilds only the part around the changing instances (IncrementalTopLevel).
class DynamicSceneAccel {
public:
    /// Builds every object BVH and the first top level. The dynamic scene must outlive this.
    /// Throws rebraid::Error for invalid settings.
    DynamicSceneAccel(const DynamicScene& scene, const DynamicSceneAccelSettings& settings);

    /// Follows the scene to its current pose (call after DynamicScene::pose()).
    DynamicFrameReport update();

    /// The structure at the current pose; replaced by update().
    const InstancedAccel& accel() const { return *accel_; }
    /// Wall time of the construction: object BVHs plus the first top.
    double build_ms() const { return build_ms_; }
    /// Reports of the dynamic meshes' last updates (index as DynamicScene::dynamic_meshes()).
    const std::vector<ObjectBvhUpdateReport>& last_updates() const { return last_updates_; }
    /// The incremental top (top = rebraid_incremental), else null.
    const IncrementalTopLevel* incremental_top() const {
        return incremental_ ? &*incremental_ : nullptr;
    }
    /// What the last incremental frame's top build did (top = rebraid_incremental); its
    /// `top` is empty, having moved into accel().
    const IncrementalTopBuild& last_incremental_build() const { return last_incremental_; }
    /// What the frames' SAH computations remembered (DynamicFrameReport::sah).
    const FrameSahCache& sah_cache() const { return sah_cache_; }

private:
    /// Builds the top level over `object_bvhs` and assembles the structure; `previous` is the
    /// last frame's incremental top, whose arrays the next one reuses (empty otherwise).
    void assemble(std::vector<ObjectBvh> object_bvhs, TopLevelBvh previous = {});

    const DynamicScene& scene_;
    DynamicSceneAccelSettings settings_;
    std::vector<ObjectBvhUpdater> updaters_;  ///< index as dynamic_meshes()
    std::vector<ObjectBvhUpdateReport> last_updates_;
    std::optional<InstancedAccel> accel_;
    std::optional<IncrementalTopLevel> incremental_;
    std::vector<InstanceId> changing_instances_;  ///< the incremental top's dynamic part
    IncrementalTopBuild last_incremental_;        ///< its top moved into accel_
    FrameSahCache sah_cache_;                     ///< static items' SAH costs
    std::vector<AffineTransform> transforms_;     ///< per instance, for the SAH
    double build_ms_ = 0.0;
};

}  // namespace rebraid
