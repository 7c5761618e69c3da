#include "rebraid/rebraiding/rebraid_termination.h"

#include <algorithm>

namespace rebraid {

bool overlaps_little(std::span<const BuildPrim> prims, float max_fraction) {
    for (std::size_t i = 0; i < prims.size(); ++i)
        for (std::size_t j = i + 1; j < prims.size(); ++j) {
            const BBox3f& a = prims[i].bounds;
            const BBox3f& b = prims[j].bounds;
            const float shared = intersection(a, b).half_area();
            if (shared > max_fraction * std::min(a.half_area(), b.half_area())) return false;
        }
    return true;
}

}  // namespace rebraid
