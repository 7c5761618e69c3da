#pragma once

#include <vector>

#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/bbox.h"

namespace rebraid {

/// The tree a wide-BVH build produces: nodes plus the root reference. Leaf references name
/// ranges of the BuildPrim array the build reordered.
struct WideBvh {
    std::vector<WideNode> nodes;
    NodeRef root = NodeRef::empty();  ///< empty for no prims; a leaf when one leaf suffices
    BBox3f bounds;
};

}  // namespace rebraid
