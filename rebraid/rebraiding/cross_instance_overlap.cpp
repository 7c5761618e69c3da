#include "rebraid/rebraiding/cross_instance_overlap.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace rebraid {
namespace {

/// Whether a and b meet in a region of positive surface area: no axis apart, and at least
/// two axes where the common interval has a length.
bool meet_in_an_area(const BBox3f& a, const BBox3f& b) {
    int long_axes = 0;
    for (int axis = 0; axis < 3; ++axis) {
        const float length =
            std::min(a.max[axis], b.max[axis]) - std::max(a.min[axis], b.min[axis]);
        if (!(length >= 0.0f)) return false;
        long_axes += length > 0.0f;
    }
    return long_axes >= 2;
}

}  // namespace

bool has_cross_instance_overlap(std::span<const BuildPrim> prims,
                                std::span<const BRefTarget> targets) {
    if (prims.size() < 2) return false;
    // Where instances crowd together the first box usually meets another instance's: one
    // pass settles it without sorting.
    const InstanceId first_instance = targets[prims.front().id].instance_id;
    for (std::size_t i = 1; i < prims.size(); ++i)
        if (targets[prims[i].id].instance_id != first_instance &&
            meet_in_an_area(prims.front().bounds, prims[i].bounds))
            return true;
    BBox3f bounds;
    for (const BuildPrim& prim : prims) bounds.extend(prim.bounds);
    const int axis = bounds.largest_axis();
    std::vector<std::uint32_t> order(prims.size());
    for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
        const float lo_a = prims[a].bounds.min[axis], lo_b = prims[b].bounds.min[axis];
        return lo_a < lo_b || (lo_a == lo_b && a < b);
    });
    // The boxes met so far whose interval along the axis still reaches the sweep position.
    std::vector<std::uint32_t> active;
    for (const std::uint32_t i : order) {
        const BBox3f& box = prims[i].bounds;
        const InstanceId instance = targets[prims[i].id].instance_id;
        for (std::size_t k = 0; k < active.size();) {
            const BuildPrim& other = prims[active[k]];
            if (other.bounds.max[axis] < box.min[axis]) {  // behind the sweep for good
                active[k] = active.back();
                active.pop_back();
                continue;
            }
            if (targets[other.id].instance_id != instance && meet_in_an_area(box, other.bounds))
                return true;
            ++k;
        }
        active.push_back(i);
    }
    return false;
}

}  // namespace rebraid
