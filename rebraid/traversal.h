#pragma once

#include <cmath>
#include <cstdint>

#include "rebraid/accel.h"
#include "rebraid/ray.h"
#include "rebraid/wide_node.h"

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#define REBRAID_SIMD_AVX2 1
#endif

namespace rebraid {

/// A ray prepared for box tests: reciprocal direction with zero components replaced by tiny
/// ones (so no 0 * inf appears) and, per axis, whether the near plane is the lower one.
struct TraversalRay {
    Vec3f org;
    Vec3f dir;
    Vec3f rdir;
    float tnear = 0.0f;
    float tfar = 0.0f;
    int near_is_lower[3] = {1, 1, 1};

    TraversalRay(Vec3f origin, Vec3f direction, float t_near, float t_far)
        : org(origin), dir(direction), tnear(t_near), tfar(t_far) {
        for (int a = 0; a < 3; ++a) {
            const float d = direction[a];
            const float safe = std::fabs(d) < 1e-18f ? std::copysign(1e-18f, d) : d;
            rdir[a] = 1.0f / safe;
            near_is_lower[a] = rdir[a] >= 0.0f;
        }
    }
};

/// Distances to the children's boxes a ray enters before `tfar`; bit i of the result is set
/// when child i is hit, with its entry distance in `distances[i]`.
/// The far distance is scaled up by 1 + 2*gamma(3) (Ize 2013) so rounding in the slab test
/// can never reject a box the ray touches.
inline unsigned intersect_node(const WideNode& node, const TraversalRay& ray,
                               float distances[kBvhWidth]) {
    constexpr float kRobustScale = 1.0f + 4.0f * 5.96046448e-08f;
#ifdef REBRAID_SIMD_AVX2
    const float* planes[2][3] = {{node.upper_x, node.upper_y, node.upper_z},
                                 {node.lower_x, node.lower_y, node.lower_z}};
    __m256 t_enter = _mm256_set1_ps(ray.tnear);
    __m256 t_exit = _mm256_set1_ps(ray.tfar);
    for (int a = 0; a < 3; ++a) {
        const __m256 org = _mm256_set1_ps(ray.org[a]);
        const __m256 rdir = _mm256_set1_ps(ray.rdir[a]);
        const __m256 near_plane = _mm256_load_ps(planes[ray.near_is_lower[a]][a]);
        const __m256 far_plane = _mm256_load_ps(planes[1 - ray.near_is_lower[a]][a]);
        t_enter = _mm256_max_ps(t_enter, _mm256_mul_ps(_mm256_sub_ps(near_plane, org), rdir));
        t_exit = _mm256_min_ps(t_exit, _mm256_mul_ps(_mm256_sub_ps(far_plane, org), rdir));
    }
    t_exit = _mm256_mul_ps(t_exit, _mm256_set1_ps(kRobustScale));
    _mm256_storeu_ps(distances, t_enter);
    return unsigned(_mm256_movemask_ps(_mm256_cmp_ps(t_enter, t_exit, _CMP_LE_OQ)));
#else
    const float* lower[3] = {node.lower_x, node.lower_y, node.lower_z};
    const float* upper[3] = {node.upper_x, node.upper_y, node.upper_z};
    unsigned mask = 0;
    for (int i = 0; i < kBvhWidth; ++i) {
        float t_enter = ray.tnear, t_exit = ray.tfar;
        for (int a = 0; a < 3; ++a) {
            const float near_plane = ray.near_is_lower[a] ? lower[a][i] : upper[a][i];
            const float far_plane = ray.near_is_lower[a] ? upper[a][i] : lower[a][i];
            t_enter = std::fmax(t_enter, (near_plane - ray.org[a]) * ray.rdir[a]);
            t_exit = std::fmin(t_exit, (far_plane - ray.org[a]) * ray.rdir[a]);
        }
        distances[i] = t_enter;
        if (t_enter <= t_exit * kRobustScale) mask |= 1u << i;
    }
    return mask;
#endif
}

/// Ordered depth-first traversal of the wide BVH `nodes` from `start` (any node, or a leaf
/// reference). `visit_leaf(NodeRef leaf)` tests a leaf's primitives, shrinking ray.tfar on
/// hits, and returns true to stop traversal (any-hit queries). Children are visited nearest
/// first; stacked subtrees farther than the current tfar are skipped. Returns whether
/// traversal was stopped by visit_leaf.
template <class LeafVisitor>
bool traverse_bvh(const WideNode* nodes, NodeRef start, TraversalRay& ray,
                  TraversalCounters* counters, LeafVisitor&& visit_leaf) {
    struct Entry {
        NodeRef ref;
        float distance;
    };
    // Each wide level pushes at most kBvhWidth - 1 entries.
    Entry stack[kMaxBvhDepth * (kBvhWidth - 1) + 1];
    int stack_size = 0;
    NodeRef current = start;
    for (;;) {
        while (current.is_inner()) {
            const WideNode& node = nodes[current.node_id()];
            if (counters) ++counters->nodes_visited;
            alignas(32) float distances[kBvhWidth];
            unsigned mask = intersect_node(node, ray, distances);
            if (mask == 0) {
                current = NodeRef::empty();
                break;
            }
            int first = __builtin_ctz(mask);
            mask &= mask - 1;
            if (mask == 0) {  // one child hit: descend without touching the stack
                current = node.children[first];
                continue;
            }
            // Several hits: sort them far to near, push all but the nearest.
            Entry hits[kBvhWidth];
            int hit_count = 0;
            hits[hit_count++] = {node.children[first], distances[first]};
            while (mask) {
                const int slot = __builtin_ctz(mask);
                mask &= mask - 1;
                Entry entry{node.children[slot], distances[slot]};
                int j = hit_count++;
                while (j > 0 && hits[j - 1].distance < entry.distance) {
                    hits[j] = hits[j - 1];
                    --j;
                }
                hits[j] = entry;
            }
            for (int i = 0; i < hit_count - 1; ++i) stack[stack_size++] = hits[i];
            current = hits[hit_count - 1].ref;
        }
        if (current.is_leaf() && visit_leaf(current)) return true;
        // Pop the nearest stacked subtree that may still hold a closer hit.
        current = NodeRef::empty();
        while (stack_size > 0) {
            const Entry& entry = stack[--stack_size];
            if (entry.distance <= ray.tfar) {
                current = entry.ref;
                break;
            }
        }
        if (current.is_empty()) return false;
    }
}

}  // namespace rebraid
