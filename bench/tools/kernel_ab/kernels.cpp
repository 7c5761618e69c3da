// The kernels under comparison: compiled twice by bench/tools/kernel_ab.py, once against an
// earlier revision's headers (its SIMD namespace renamed) and once against the working tree,
// each time defining KERNEL_AB_RUN as that copy's entry point. Include nowhere else.
#include <chrono>
#include <vector>

#include "rebraid/top_level/trace_kernel_bodies.h"

namespace kernel_ab {

using namespace rebraid;

/// Every ray's closest hit through the instanced query `closest_hit`, plain or located.
template <auto closest_hit>
double sum_instanced_hits(const InstancedAccel& accel, const std::vector<Ray>& rays, bool located) {
    double sum = 0.0;
    for (const Ray& ray : rays) {
        const Hit hit = located ? intersect_located_entry<closest_hit>(accel, ray, nullptr).hit
                                : intersect_entry<closest_hit>(accel, ray, nullptr);
        if (hit.is_hit()) sum += hit.t;
    }
    return sum;
}

/// Every ray's closest hit through the merged query the structure takes: with the items entered
/// in the loop or out of line (MergedTopLevel::enters_items_out_of_line), in revisions that
/// have both, else the one merged query.
template <TriangleTest kTest, class Accel>
double sum_merged_hits(const Accel& accel, const std::vector<Ray>& rays, bool located) {
    if constexpr (requires { &merged_closest_hit<kTest, true>; }) {
        if (accel.merged_top_level().enters_items_out_of_line)
            return sum_instanced_hits<&merged_closest_hit<kTest, true>>(accel, rays, located);
        return sum_instanced_hits<&merged_closest_hit<kTest, false>>(accel, rays, located);
    } else {
        return sum_instanced_hits<&merged_closest_hit<kTest>>(accel, rays, located);
    }
}

/// Closest hits of `rays` through the kernels this copy was compiled with: the query the
/// structure takes (as InstancedAccel::use_kernels chooses it: one item, merged, or the
/// general one; the flat query for a flat structure), located when asked, as the Embree glue
/// asks. Returns the seconds taken and the sum of the hits' t in `t_sum`.
double KERNEL_AB_RUN(const FlatAccel* flat, const InstancedAccel* instanced,
                     const std::vector<Ray>& rays, bool located, double& t_sum) {
    constexpr TriangleTest kTest = TriangleTest::moller;
    const auto start = std::chrono::steady_clock::now();
    if (flat != nullptr) {
        t_sum = 0.0;
        for (const Ray& ray : rays) {
            const Hit hit = flat_intersect<kTest>(*flat, ray, nullptr);
            if (hit.is_hit()) t_sum += hit.t;
        }
    } else if (const NodeRef root = instanced->top_level().root;
               root.is_leaf() && root.prim_count() == 1) {
        t_sum = sum_instanced_hits<&sole_item_closest_hit<kTest>>(*instanced, rays, located);
    } else if (!instanced->merged_top_level().empty()) {
        t_sum = sum_merged_hits<kTest>(*instanced, rays, located);
    } else {
        t_sum = sum_instanced_hits<&instanced_closest_hit<kTest>>(*instanced, rays, located);
    }
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace kernel_ab
