#pragma once

#include <cstdint>
#include <span>
#include <utility>

#include "rebraid/rebraiding/bref.h"
#include "rebraid/rebraiding/rebraid_settings.h"

namespace rebraid {

/// Extra BRef slots the build may fill by opening (paper §5.2), under the settings' rule:
/// budget_factor x instances, instanced primitives / primitives_per_bref, or the larger of
/// the two. Capped twice, so
/// the BRef array (allocated in full up front) stays bounded for any budget_factor:
/// - at instanced primitives - instances: every leaf holds at least one primitive, so opening
///   every BRef down to the leaves cannot make more BRefs than primitives (with Embree's
///   spatial splits a primitive may sit in several leaves; opening then stops at the budget);
/// - at settings.max_budget.
std::uint64_t bref_budget(const RebraidSettings& settings, std::uint64_t instance_count,
                          std::uint64_t instanced_primitive_count);

/// Paper §5.2: after `parent` was partitioned at `mid`, gives its free space to the two
/// children in proportion to how many of their BRefs meet the opening criterion
/// (`left_openable`, `right_openable`; by BRef counts when neither has any), and moves the
/// right child's BRefs right to make room for the left child's share (in place, not keeping
/// their order). The split depends only on the counts, never on thread timing, so the tree
/// is the same for any thread count, and no subtree can ever open more than its share.
std::pair<BRefSegment, BRefSegment> split_free_space(const BRefSegment& parent, std::uint32_t mid,
                                                     std::uint32_t left_openable,
                                                     std::uint32_t right_openable,
                                                     std::span<BuildPrim> prims);

}  // namespace rebraid
