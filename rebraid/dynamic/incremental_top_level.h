#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/core/scene.h"
#include "rebraid/dynamic/static_top_cut.h"
#include "rebraid/rebraiding/rebraid_builder.h"
#include "rebraid/rebraiding/rebraid_settings.h"
#include "rebraid/top_level/top_level_bvh.h"

namespace rebraid {

/// Parameters of IncrementalTopLevel (beyond the re-braiding settings it shares with
/// build_rebraid).
struct IncrementalTopSettings {
    /// Most pieces of the static top (kept subtrees and static items) each frame's upper
    /// build may take: the cut opens the static subtrees that overlap dynamic BRefs, largest
    /// first, until none is left or this many pieces are reached. More pieces let the upper
    /// build interleave more static items with the dynamic ones (a lower SAH) at a higher
    /// per-frame cost; the upper build is binned SAH over pieces plus dynamic BRefs.
    std::uint32_t max_cut_pieces = 4096;
    /// Size the static top's opening budget for the whole scene, as a full re-braid would
    /// (budget_factor x all instances, or all instanced primitives / primitives_per_bref),
    /// instead of for the static instances alone. A full build spends most of its budget on
    /// large static instances, which small dynamic ones leave unopened; without this, a few
    /// static instances among many dynamic ones would get a fraction of that budget (measured
    /// on powerplant: 5% higher SAH). The dynamic part gets its own budget on top.
    bool static_budget_for_whole_scene = true;

    /// Throws rebraid::Error naming the field and value when a setting is out of range.
    void validate() const;
};

/// What one frame's top level is and what building it did.
struct IncrementalTopBuild {
    /// The frame's top: the static top's nodes and items first, unchanged (the kept subtrees
    /// are referenced in place; the nodes above the cut stay unreferenced), then the new upper
    /// nodes; the static items, then the dynamic BRefs. Traversed as any TopLevelBvh.
    TopLevelBvh top;
    std::uint64_t brefs = 0;       ///< items: static plus dynamic BRefs
    std::uint64_t budget = 0;      ///< opening budgets of the static and the dynamic build
    std::uint64_t opened = 0;      ///< BRefs opened by the static (once) and the dynamic build
    std::uint32_t cut_pieces = 0;  ///< pieces of the static top the upper build took
    std::uint32_t opened_static_nodes = 0;  ///< static nodes the cut replaced by children
    std::uint64_t dynamic_brefs = 0;        ///< BRefs of the dynamic instances
    /// True when the grafted tree would have been deeper than the traversal allows and the
    /// frame was re-braided in full instead (never seen on real scenes; kept for safety).
    bool is_full_rebraid = false;
};

/// An incremental re-braided top level for scenes where most instances stand still: the static instances' re-braided top is built once; every frame
/// re-braids only the dynamic instances, cuts the static top where it overlaps their BRefs
/// (cut_static_top), and builds a small binned-SAH tree over the cut's pieces plus the
/// dynamic BRefs whose leaves point at the kept static subtrees in place. The result is an
/// ordinary top level for the unchanged traversal. Deterministic: the same inputs give the
/// same tree for any thread count.
class IncrementalTopLevel {
public:
    /// Throws rebraid::Error for invalid settings.
    explicit IncrementalTopLevel(const RebraidSettings& rebraid = {},
                                 const IncrementalTopSettings& settings = {});

    /// (Re)builds the static top over `static_instances` of `scene` (build_rebraid over that
    /// subset). Call once, and again whenever the static set, its transforms or its meshes'
    /// BVHs change. Throws rebraid::Error for an instance id past the scene's instances.
    void build_static(const Scene& scene, std::span<const ObjectBvh> object_bvhs,
                      std::span<const InstanceId> static_instances);

    /// The top level of one frame over the static instances and `dynamic_instances`.
    /// Preconditions: build_static() ran with the same static instances, transforms and object
    /// BVHs (the dynamic ones may change freely). Throws rebraid::Error when build_static()
    /// has not run, or a dynamic instance is static or out of range.
    IncrementalTopBuild build_frame(const Scene& scene, std::span<const ObjectBvh> object_bvhs,
                                    std::span<const InstanceId> dynamic_instances) const;
    /// As above, building the frame's top in `previous`: either empty (the static top is
    /// copied, as above) or the top of an earlier build_frame() of this object since the last
    /// build_static() that was not a full re-braid. Such a top starts with the static top,
    /// which no frame changes, so its arrays are cut back to it and only the frame's part is
    /// appended, instead of copying the static top (about 10 MB for 20,000 static instances)
    /// into new arrays every frame. The result equals the one of the overload above. Throws
    /// rebraid::Error when `previous` is visibly not such a top (shorter than the static top,
    /// or differing from it at the nodes and items it samples).
    IncrementalTopBuild build_frame(const Scene& scene, std::span<const ObjectBvh> object_bvhs,
                                    std::span<const InstanceId> dynamic_instances,
                                    TopLevelBvh previous) const;

    /// The static top (empty before build_static()).
    const TopLevelBvh& static_top() const { return static_.top; }
    /// How often build_static() ran: the static work is done once, not per frame.
    std::uint64_t static_build_count() const { return static_build_count_; }
    /// Wall time of the last build_static().
    double static_build_ms() const { return static_build_ms_; }

private:
    /// Throws rebraid::Error unless `top` visibly starts with the static top.
    void check_starts_with_static_top(const TopLevelBvh& top) const;

    RebraidSettings rebraid_;
    IncrementalTopSettings settings_;
    RebraidBuild static_;
    StaticTopSummary summary_;
    std::vector<InstanceId> static_instances_;
    std::vector<char> is_static_;  ///< index = InstanceId
    std::uint64_t static_build_count_ = 0;
    double static_build_ms_ = 0.0;
};

}  // namespace rebraid
