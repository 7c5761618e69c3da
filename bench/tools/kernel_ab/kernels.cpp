// The kernels under comparison: compiled twice by bench/tools/kernel_ab.py, once against an
// earlier revision's headers (its SIMD namespace renamed) and once against the working tree,
// each time defining KERNEL_AB_RUN as that copy's entry point. Include nowhere else.
#include <chrono>
#include <vector>

#include "rebraid/top_level/trace_kernel_bodies.h"

namespace kernel_ab {

using namespace rebraid;

/// Closest hits of `rays` through the kernels this copy was compiled with (the flat query,
/// the merged or the general instanced one, located when asked, as the Embree glue asks);
/// returns the seconds taken and the sum of the hits' t in `t_sum`.
double KERNEL_AB_RUN(const FlatAccel* flat, const InstancedAccel* instanced,
                     const std::vector<Ray>& rays, bool located, double& t_sum) {
    constexpr TriangleTest kTest = TriangleTest::moller;
    const auto start = std::chrono::steady_clock::now();
    double sum = 0.0;
    const auto add = [&sum](const Hit& hit) {
        if (hit.is_hit()) sum += hit.t;
    };
    if (flat != nullptr) {
        for (const Ray& ray : rays) add(flat_intersect<kTest>(*flat, ray, nullptr));
    } else if (!instanced->merged_top_level().empty()) {
        for (const Ray& ray : rays)
            add(located
                    ? intersect_located_entry<&merged_closest_hit<kTest>>(*instanced, ray, nullptr)
                          .hit
                    : intersect_entry<&merged_closest_hit<kTest>>(*instanced, ray, nullptr));
    } else {
        for (const Ray& ray : rays)
            add(located ? intersect_located_entry<&instanced_closest_hit<kTest>>(*instanced, ray,
                                                                                 nullptr)
                              .hit
                        : intersect_entry<&instanced_closest_hit<kTest>>(*instanced, ray, nullptr));
    }
    t_sum = sum;
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace kernel_ab
