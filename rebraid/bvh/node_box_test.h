#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "rebraid/bvh/traversal_ray.h"
#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/simd_config.h"

namespace rebraid {
inline namespace REBRAID_SIMD_NAMESPACE {

// The box-test kernels of traverse_bvh. Each comes in the SIMD level the library is compiled
// for (simd_config.h) and a portable form: the same arithmetic, and both conservative
// (SlabShifts), so the same hits; the traversal loop itself never names an ISA.

#ifdef REBRAID_SIMD_AVX2

/// The box test of one ray against the 8 children of a node: the per-ray values broadcast
/// once per traversal rather than per node.
class NodeBoxTest {
public:
    explicit NodeBoxTest(const TraversalRay& ray)
        : tnear_(_mm256_set1_ps(ray.tnear)), planes_(&ray.plane_offsets()) {
        for (int a = 0; a < 3; ++a) {
            rdir_[a] = _mm256_set1_ps(ray.rdir[a]);
            near_shift_[a] = _mm256_set1_ps(ray.shifts.near[a]);
            far_shift_[a] = _mm256_set1_ps(ray.shifts.far[a]);
        }
    }

    /// Mask of the children the ray enters within [tnear, tfar] (tnear the prepared ray's,
    /// which no query changes: broadcast once here rather than per node), with every child's
    /// entry distance in `distances` (32-byte aligned). Every step is chosen for the latency
    /// of the chain each node waits on:
    /// - the distance to a plane is one fused multiply-add, plane * rdir + shift, with the
    ///   plane read straight into it and the shifts (SlabShifts) keeping it conservative
    ///   without a scale on tfar or a multiply after the min;
    /// - max and min are integer operations on the float bits: the same as the float ones on
    ///   the non-negative distances that decide (with tnear >= 0 the entry never shows a zero's
    ///   sign), and on negative ones they err towards entering (a smaller entry, a larger
    ///   exit), never towards rejecting a box the ray touches.
    unsigned operator()(const WideNode& node, float tfar, float* distances) const {
        const char* base = reinterpret_cast<const char*>(&node);
        const auto slab = [&](std::uint32_t offset, int axis, const __m256& shift) {
            const __m256 plane = _mm256_load_ps(reinterpret_cast<const float*>(base + offset));
            return _mm256_fmadd_ps(plane, rdir_[axis], shift);
        };
        const __m256 near_x = slab(planes_->near[0], 0, near_shift_[0]);
        const __m256 near_y = slab(planes_->near[1], 1, near_shift_[1]);
        const __m256 near_z = slab(planes_->near[2], 2, near_shift_[2]);
        const __m256 far_x = slab(planes_->far[0], 0, far_shift_[0]);
        const __m256 far_y = slab(planes_->far[1], 1, far_shift_[1]);
        const __m256 far_z = slab(planes_->far[2], 2, far_shift_[2]);
        const auto bits = [](__m256 v) { return _mm256_castps_si256(v); };
        const __m256 entry =
            _mm256_castsi256_ps(_mm256_max_epi32(_mm256_max_epi32(bits(near_x), bits(near_y)),
                                                 _mm256_max_epi32(bits(near_z), bits(tnear_))));
        const __m256 exit = _mm256_castsi256_ps(
            _mm256_min_epi32(_mm256_min_epi32(bits(far_x), bits(far_y)),
                             _mm256_min_epi32(bits(far_z), bits(_mm256_set1_ps(tfar)))));
        _mm256_store_ps(distances, entry);
        return unsigned(_mm256_movemask_ps(_mm256_cmp_ps(entry, exit, _CMP_LE_OQ)));
    }

private:
    __m256 tnear_;
    __m256 rdir_[3];
    __m256 near_shift_[3];
    __m256 far_shift_[3];
    const SlabPlaneOffsets* planes_;
};

/// Bit i set when distances[i] (32-byte aligned, as NodeBoxTest wrote them) is at most
/// `tfar`: the children still entered before the end of a ray that hits have shortened.
inline unsigned entered_before(const float* distances, float tfar) {
    return unsigned(_mm256_movemask_ps(
        _mm256_cmp_ps(_mm256_load_ps(distances), _mm256_set1_ps(tfar), _CMP_LE_OQ)));
}

/// Bit i set when child i of `node` is a leaf reference.
inline unsigned leaf_slots(const WideNode& node) {
    // The leaf flag is each reference's top bit, i.e. the sign bit of the 8 lanes.
    static_assert(offsetof(WideNode, children) % 32 == 0 && NodeRef::kLeafBit == 0x80000000u);
    return unsigned(
        _mm256_movemask_ps(_mm256_load_ps(reinterpret_cast<const float*>(node.children))));
}

#else  // portable: one child after the other, the same arithmetic

class NodeBoxTest {
public:
    explicit NodeBoxTest(const TraversalRay& ray) : ray_(ray), planes_(ray.plane_offsets()) {}

    unsigned operator()(const WideNode& node, float tfar, float* distances) const {
        const char* base = reinterpret_cast<const char*>(&node);
        const auto plane = [&](std::uint32_t offset, int slot) {
            return reinterpret_cast<const float*>(base + offset)[slot];
        };
        unsigned mask = 0;
        for (int i = 0; i < kBvhWidth; ++i) {
            float t_enter = ray_.tnear, t_exit = tfar;
            for (int a = 0; a < 3; ++a) {
                t_enter = std::fmax(t_enter, std::fma(plane(planes_.near[a], i), ray_.rdir[a],
                                                      ray_.shifts.near[a]));
                t_exit = std::fmin(
                    t_exit, std::fma(plane(planes_.far[a], i), ray_.rdir[a], ray_.shifts.far[a]));
            }
            distances[i] = t_enter;
            if (t_enter <= t_exit) mask |= 1u << i;
        }
        return mask;
    }

private:
    const TraversalRay& ray_;
    const SlabPlaneOffsets& planes_;
};

inline unsigned entered_before(const float* distances, float tfar) {
    unsigned entered = 0;
    for (int i = 0; i < kBvhWidth; ++i) entered |= unsigned(distances[i] <= tfar) << i;
    return entered;
}

inline unsigned leaf_slots(const WideNode& node) {
    unsigned slots = 0;
    for (int i = 0; i < kBvhWidth; ++i) slots |= unsigned(node.children[i].is_leaf()) << i;
    return slots;
}

#endif

}  // namespace REBRAID_SIMD_NAMESPACE
}  // namespace rebraid
