#pragma once

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "rebraid/accel.h"
#include "rebraid/ray.h"
#include "rebraid/simd_config.h"
#include "rebraid/wide_node.h"

namespace rebraid {
inline namespace REBRAID_SIMD_NAMESPACE {

/// A ray prepared for box tests: reciprocal direction with zero components replaced by tiny
/// ones (so no 0 * inf appears) and, per axis, the byte offsets inside a WideNode of the
/// plane arrays the ray enters (near) and leaves (far) a box through.
struct TraversalRay {
    Vec3f org;
    Vec3f dir;
    Vec3f rdir;
    float tnear = 0.0f;
    float tfar = 0.0f;
    std::uint32_t near_offset[3] = {};
    std::uint32_t far_offset[3] = {};

    TraversalRay(Vec3f origin, Vec3f direction, float t_near, float t_far)
        : org(origin), dir(direction), tnear(t_near), tfar(t_far) {
        // WideNode stores each axis's lower plane array followed by its upper one.
        static_assert(offsetof(WideNode, upper_x) == offsetof(WideNode, lower_x) + 32 &&
                      offsetof(WideNode, lower_y) == offsetof(WideNode, lower_x) + 64 &&
                      offsetof(WideNode, upper_y) == offsetof(WideNode, lower_x) + 96 &&
                      offsetof(WideNode, lower_z) == offsetof(WideNode, lower_x) + 128 &&
                      offsetof(WideNode, upper_z) == offsetof(WideNode, lower_x) + 160);
        constexpr std::uint32_t kLowerX = offsetof(WideNode, lower_x);
        for (int a = 0; a < 3; ++a) {
            const float d = direction[a];
            const float safe = std::fabs(d) < 1e-18f ? std::copysign(1e-18f, d) : d;
            rdir[a] = 1.0f / safe;
            const std::uint32_t is_negative = rdir[a] >= 0.0f ? 0u : 1u;
            near_offset[a] = kLowerX + 64u * std::uint32_t(a) + 32u * is_negative;
            far_offset[a] = kLowerX + 64u * std::uint32_t(a) + 32u * (1u - is_negative);
        }
    }
};

/// The far distance of a slab test is scaled up by 1 + 2*gamma(3) (Ize 2013) so rounding can
/// never reject a box the ray touches.
inline constexpr float kRobustBoxScale = 1.0f + 4.0f * 5.96046448e-08f;

#ifdef REBRAID_SIMD_AVX2
/// The per-ray values of the box test, broadcast once per traversal rather than per node.
struct NodeTestRay {
    __m256 org[3];
    __m256 rdir[3];
    std::uint32_t near_offset[3];
    std::uint32_t far_offset[3];

    explicit NodeTestRay(const TraversalRay& ray) {
        for (int a = 0; a < 3; ++a) {
            org[a] = _mm256_set1_ps(ray.org[a]);
            rdir[a] = _mm256_set1_ps(ray.rdir[a]);
            near_offset[a] = ray.near_offset[a];
            far_offset[a] = ray.far_offset[a];
        }
    }
};

/// Entry distances of all children (as a vector) and the mask of those the ray enters within
/// [tnear, tfar]. (plane - org) * rdir rather than a fused multiply-add: the product of a
/// far-away origin and rdir would cost the precision the robust bound relies on.
inline unsigned intersect_node_simd(const WideNode& node, const NodeTestRay& ray, float tnear,
                                    float tfar, __m256& entry) {
    const char* base = reinterpret_cast<const char*>(&node);
    const auto plane = [&](std::uint32_t offset) {
        return _mm256_load_ps(reinterpret_cast<const float*>(base + offset));
    };
    const __m256 near_x =
        _mm256_mul_ps(_mm256_sub_ps(plane(ray.near_offset[0]), ray.org[0]), ray.rdir[0]);
    const __m256 near_y =
        _mm256_mul_ps(_mm256_sub_ps(plane(ray.near_offset[1]), ray.org[1]), ray.rdir[1]);
    const __m256 near_z =
        _mm256_mul_ps(_mm256_sub_ps(plane(ray.near_offset[2]), ray.org[2]), ray.rdir[2]);
    const __m256 far_x =
        _mm256_mul_ps(_mm256_sub_ps(plane(ray.far_offset[0]), ray.org[0]), ray.rdir[0]);
    const __m256 far_y =
        _mm256_mul_ps(_mm256_sub_ps(plane(ray.far_offset[1]), ray.org[1]), ray.rdir[1]);
    const __m256 far_z =
        _mm256_mul_ps(_mm256_sub_ps(plane(ray.far_offset[2]), ray.org[2]), ray.rdir[2]);
    entry =
        _mm256_max_ps(_mm256_max_ps(near_x, near_y), _mm256_max_ps(near_z, _mm256_set1_ps(tnear)));
    const __m256 exit =
        _mm256_min_ps(_mm256_min_ps(far_x, far_y), _mm256_min_ps(far_z, _mm256_set1_ps(tfar)));
    const __m256 robust_exit = _mm256_mul_ps(exit, _mm256_set1_ps(kRobustBoxScale));
    return unsigned(_mm256_movemask_ps(_mm256_cmp_ps(entry, robust_exit, _CMP_LE_OQ)));
}
#endif

/// Distances to the children's boxes a ray enters before `tfar`; bit i of the result is set
/// when child i is hit, with its entry distance in `distances[i]`.
inline unsigned intersect_node(const WideNode& node, const TraversalRay& ray,
                               float distances[kBvhWidth]) {
#ifdef REBRAID_SIMD_AVX2
    __m256 entry;
    const unsigned mask = intersect_node_simd(node, NodeTestRay(ray), ray.tnear, ray.tfar, entry);
    _mm256_storeu_ps(distances, entry);
    return mask;
#else
    const char* base = reinterpret_cast<const char*>(&node);
    const auto plane = [&](std::uint32_t offset, int slot) {
        return reinterpret_cast<const float*>(base + offset)[slot];
    };
    unsigned mask = 0;
    for (int i = 0; i < kBvhWidth; ++i) {
        float t_enter = ray.tnear, t_exit = ray.tfar;
        for (int a = 0; a < 3; ++a) {
            t_enter = std::fmax(t_enter, (plane(ray.near_offset[a], i) - ray.org[a]) * ray.rdir[a]);
            t_exit = std::fmin(t_exit, (plane(ray.far_offset[a], i) - ray.org[a]) * ray.rdir[a]);
        }
        distances[i] = t_enter;
        if (t_enter <= t_exit * kRobustBoxScale) mask |= 1u << i;
    }
    return mask;
#endif
}

/// How traverse_bvh orders the children a ray enters.
enum class TraversalOrder {
    /// Nearest child first, farther ones stacked with their entry distance and skipped when a
    /// hit closer than that distance was found meanwhile: closest-hit queries.
    nearest_first,
    /// Children in slot order, no sorting: any-hit queries, where the first hit ends the
    /// traversal and ordering costs more than it saves.
    any,
};

/// Asks the cache for the node `ref` names (all four lines of its 224 bytes).
inline void prefetch_node(const WideNode* nodes, NodeRef ref) {
    const char* base = reinterpret_cast<const char*>(nodes + ref.node_id());
    for (int offset = 0; offset < int(sizeof(WideNode)); offset += 64)
        __builtin_prefetch(base + offset);
}

/// A leaf prefetcher that does nothing (traverse_bvh's default).
struct NoLeafPrefetch {
    void operator()(NodeRef) const {}
};

/// Depth-first traversal of the wide BVH `nodes` from `start` (any node, or a leaf
/// reference). `visit_leaf(NodeRef leaf)` tests a leaf's primitives, shrinking ray.tfar on
/// hits, and returns true to stop traversal (any-hit queries). Returns whether traversal was
/// stopped by visit_leaf.
/// `prefetch_leaf(NodeRef leaf)` is called for hit leaves that wait on the stack, and every
/// stacked inner node is prefetched: on scenes larger than the caches, the misses of the
/// siblings then overlap with the work on the nearest child instead of following it.
template <TraversalOrder order = TraversalOrder::nearest_first, class LeafVisitor,
          class LeafPrefetcher = NoLeafPrefetch>
bool traverse_bvh(const WideNode* nodes, NodeRef start, TraversalRay& ray,
                  TraversalCounters* counters, LeafVisitor&& visit_leaf,
                  LeafPrefetcher&& prefetch_leaf = {}) {
    // A stack entry packs a child's entry distance (high half, as float bits) with its
    // reference (low half); for the non-negative distances of valid rays, comparing entries
    // as integers compares distances. The array is left uninitialised on purpose: clearing
    // its ~3.8 KB per ray once cost more than the whole traversal.
    constexpr int kStackCapacity = kMaxBvhDepth * (kBvhWidth - 1) + 1;
    std::uint64_t stack[kStackCapacity];
    int stack_size = 0;
    const auto entry_ref = [](std::uint64_t entry) {
        return std::bit_cast<NodeRef>(std::uint32_t(entry));
    };
    const auto entry_distance = [](std::uint64_t entry) {
        return std::bit_cast<float>(std::uint32_t(entry >> 32));
    };
    const auto make_entry = [&](NodeRef ref, float distance) {
        if (ref.is_leaf())
            prefetch_leaf(ref);
        else
            prefetch_node(nodes, ref);
        return (std::uint64_t(std::bit_cast<std::uint32_t>(distance)) << 32) | ref.bits();
    };
#ifdef REBRAID_SIMD_AVX2
    const NodeTestRay node_ray(ray);
#endif
    NodeRef current = start;
    for (;;) {
        while (current.is_inner()) {
            const WideNode& node = nodes[current.node_id()];
            // The child references sit on the node's last cache line, which is read only once
            // the box test is done; asking for it now overlaps its miss with the test's.
            __builtin_prefetch(node.children);
            if (counters) ++counters->nodes_visited;
            alignas(32) float distances[kBvhWidth];
#ifdef REBRAID_SIMD_AVX2
            __m256 entry;
            unsigned mask = intersect_node_simd(node, node_ray, ray.tnear, ray.tfar, entry);
            _mm256_store_ps(distances, entry);
#else
            unsigned mask = intersect_node(node, ray, distances);
#endif
            if (mask == 0) {
                current = NodeRef::empty();
                break;
            }
            const int first = std::countr_zero(mask);
            mask &= mask - 1;
            if (mask == 0) {  // one child hit: descend without touching the stack
                current = node.children[first];
                continue;
            }
            if constexpr (order == TraversalOrder::any) {
                current = node.children[first];
                do {
                    const int slot = std::countr_zero(mask);
                    mask &= mask - 1;
                    stack[stack_size++] = make_entry(node.children[slot], distances[slot]);
                } while (mask);
                continue;
            }
            const int second = std::countr_zero(mask);
            mask &= mask - 1;
            if (mask == 0) {  // two hits, the most common case: stack the farther one
                const bool first_is_near = distances[first] <= distances[second];
                const int near_slot = first_is_near ? first : second;
                const int far_slot = first_is_near ? second : first;
                stack[stack_size++] = make_entry(node.children[far_slot], distances[far_slot]);
                current = node.children[near_slot];
                continue;
            }
            // Three or more: push them all, sort the pushed run far to near (insertion sort,
            // runs are short), then continue with the nearest, popped again.
            const int run_begin = stack_size;
            stack[stack_size++] = make_entry(node.children[first], distances[first]);
            mask |= 1u << second;
            do {
                const int slot = std::countr_zero(mask);
                mask &= mask - 1;
                const std::uint64_t entry_key = make_entry(node.children[slot], distances[slot]);
                int j = stack_size++;
                while (j > run_begin && stack[j - 1] < entry_key) {
                    stack[j] = stack[j - 1];
                    --j;
                }
                stack[j] = entry_key;
            } while (mask);
            current = entry_ref(stack[--stack_size]);
        }
        if (current.is_leaf() && visit_leaf(current)) return true;
        // Pop the nearest stacked subtree that may still hold a closer hit.
        for (;;) {
            if (stack_size == 0) return false;
            const std::uint64_t entry = stack[--stack_size];
            if (entry_distance(entry) <= ray.tfar) {
                current = entry_ref(entry);
                break;
            }
        }
    }
}

}  // namespace REBRAID_SIMD_NAMESPACE
}  // namespace rebraid
