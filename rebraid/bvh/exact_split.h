#pragma once

#include <span>

#include "rebraid/bvh/binned_split.h"
#include "rebraid/bvh/build_prim.h"

namespace rebraid {

/// The exact split of find_binned_split; precondition prims.size() <= kMaxExactSplitPrims.
BinnedSplit find_exact_split(std::span<const BuildPrim> prims);

/// apply_binned_split for the tiny ranges of exact splits (in place, same order), without the
/// general partition's overhead. Preconditions: split.is_exact(), prims.size() <=
/// kMaxExactSplitPrims.
SplitResult apply_exact_split(std::span<BuildPrim> prims, const BinnedSplit& split);

}  // namespace rebraid
