#pragma once

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/accel.h"
#include "rebraid/core/ray.h"
#include "rebraid/core/simd_config.h"

namespace rebraid {
inline namespace REBRAID_SIMD_NAMESPACE {

/// Byte offset inside a WideNode of the plane array of `axis` a ray enters boxes through
/// (`is_far` false) or leaves them through (true), for a direction of sign `is_negative`
/// along that axis: the lower planes first for a positive direction, the upper ones for a
/// negative one.
constexpr std::uint32_t slab_plane_offset(int axis, bool is_negative, bool is_far) {
    // WideNode stores each axis's lower plane array followed by its upper one.
    static_assert(offsetof(WideNode, upper_x) == offsetof(WideNode, lower_x) + 32 &&
                  offsetof(WideNode, lower_y) == offsetof(WideNode, lower_x) + 64 &&
                  offsetof(WideNode, upper_y) == offsetof(WideNode, lower_x) + 96 &&
                  offsetof(WideNode, lower_z) == offsetof(WideNode, lower_x) + 128 &&
                  offsetof(WideNode, upper_z) == offsetof(WideNode, lower_x) + 160);
    const bool is_upper = is_negative != is_far;
    return std::uint32_t(offsetof(WideNode, lower_x)) + 64u * std::uint32_t(axis) +
           32u * std::uint32_t(is_upper);
}

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
        for (int a = 0; a < 3; ++a) {
            const float d = direction[a];
            const float safe = std::fabs(d) < 1e-18f ? std::copysign(1e-18f, d) : d;
            rdir[a] = 1.0f / safe;
            const bool is_negative = !(rdir[a] >= 0.0f);
            near_offset[a] = slab_plane_offset(a, is_negative, false);
            far_offset[a] = slab_plane_offset(a, is_negative, true);
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
            // Derived again rather than copied from ray.near_offset/far_offset: the ray was
            // usually written just before, element by element, and the compiler reads those
            // arrays back with wider loads, which cannot be forwarded from the narrower
            // stores (a stall measured at every traversal start).
            const bool is_negative = !(ray.rdir[a] >= 0.0f);
            near_offset[a] = slab_plane_offset(a, is_negative, false);
            far_offset[a] = slab_plane_offset(a, is_negative, true);
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

/// Bit i set when child i of `node` is a leaf reference.
inline unsigned leaf_slots(const WideNode& node) {
#ifdef REBRAID_SIMD_AVX2
    // The leaf flag is each reference's top bit, i.e. the sign bit of the 8 lanes.
    static_assert(offsetof(WideNode, children) % 32 == 0 && NodeRef::kLeafBit == 0x80000000u);
    return unsigned(
        _mm256_movemask_ps(_mm256_load_ps(reinterpret_cast<const float*>(node.children))));
#else
    unsigned slots = 0;
    for (int i = 0; i < kBvhWidth; ++i) slots |= unsigned(node.children[i].is_leaf()) << i;
    return slots;
#endif
}

/// How traverse_bvh hands leaves to its visitor.
enum class LeafVisits {
    /// A leaf is a child like an inner node: stacked and visited nearest first, one at a
    /// time, as visit_leaf(NodeRef leaf). For costly leaves (top-level items, each entering
    /// an object BVH), where visiting the nearest first saves whole object traversals.
    one_by_one,
    /// At an inner node, the leaf children the ray enters are handed over together, before
    /// the node's inner children, as visit_leaf(const NodeRef* refs, unsigned slots) (bit i
    /// of slots selects refs[i]); a leaf start arrives as visit_leaf(&start, 1). For leaves
    /// of a few triangles: one SIMD test then serves the triangles of several sibling
    /// leaves, where one test per leaf cost a whole test for one or two triangles (the
    /// builder's leaves hold 1.3-2 triangles on average), and the hits found shorten the
    /// ray before any inner sibling is entered.
    with_siblings,
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
/// reference). `visit_leaf` tests leaves' primitives (one leaf or several, see LeafVisits),
/// shrinking ray.tfar on hits, and returns true to stop traversal (any-hit queries). Returns
/// whether traversal was stopped by visit_leaf.
/// `prefetch_leaf(NodeRef leaf)` is called for hit leaves that wait on the stack (only with
/// LeafVisits::one_by_one), and every stacked inner node is prefetched: on scenes larger
/// than the caches, the misses of the siblings then overlap with the work on the nearest
/// child instead of following it.
template <TraversalOrder order = TraversalOrder::nearest_first,
          LeafVisits leaf_visits = LeafVisits::one_by_one, class LeafVisitor,
          class LeafPrefetcher = NoLeafPrefetch>
bool traverse_bvh(const WideNode* nodes, NodeRef start, TraversalRay& ray,
                  TraversalCounters* counters, LeafVisitor&& visit_leaf,
                  LeafPrefetcher&& prefetch_leaf = {}) {
    constexpr bool kWithSiblings = leaf_visits == LeafVisits::with_siblings;
    if constexpr (kWithSiblings) {
        if (start.is_leaf()) return visit_leaf(&start, 1u);
    }
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
            if constexpr (kWithSiblings) {
                const unsigned leaf_mask = mask & leaf_slots(node);
                if (leaf_mask != 0) {
                    if (visit_leaf(node.children, leaf_mask)) return true;
                        // Their hits shortened the ray: keep the inner children still entered
                        // before its end (the test a stacked child gets when popped).
#ifdef REBRAID_SIMD_AVX2
                    const unsigned entered = unsigned(_mm256_movemask_ps(
                        _mm256_cmp_ps(entry, _mm256_set1_ps(ray.tfar), _CMP_LE_OQ)));
#else
                    unsigned entered = 0;
                    for (int i = 0; i < kBvhWidth; ++i)
                        entered |= unsigned(distances[i] <= ray.tfar) << i;
#endif
                    mask &= ~leaf_mask & entered;
                }
            }
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
        if constexpr (!kWithSiblings) {
            if (current.is_leaf() && visit_leaf(current)) return true;
        }
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
