#include "rebraid/bvh/vertex_world_bounds.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <utility>

#include "rebraid/bvh/leaf_rows.h"

#ifdef __AVX2__
#include <immintrin.h>
#endif

namespace rebraid {
namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

/// ax bx + ay by + az bz, rounded the one way every projection of the search uses (the SIMD
/// forms below included), whatever the compiler would contract: with fused multiply-adds
/// where the target has them, as (ax bx + ay by) + az bz otherwise.
float sum_of_products(float ax, float bx, float ay, float by, float az, float bz) {
#ifdef __FMA__
    return std::fma(az, bz, std::fma(ax, bx, ay * by));
#else
    return (ax * bx + ay * by) + az * bz;
#endif
}

/// d · p.
float project(Vec3f d, Vec3f p) {
    return sum_of_products(d.x, p.x, d.y, p.y, d.z, p.z);
}

/// The largest d · p over the corners of `box`: an upper bound for every point inside.
float box_bound(const BBox3f& box, Vec3f d) {
    return sum_of_products(d.x, d.x > 0.0f ? box.max.x : box.min.x, d.y,
                           d.y > 0.0f ? box.max.y : box.min.y, d.z,
                           d.z > 0.0f ? box.max.z : box.min.z);
}

/// A support value being searched: the best vertex projection found, and the largest bound
/// of a subtree skipped within the tolerance.
struct Support {
    float best = -std::numeric_limits<float>::infinity();
    float skipped = -std::numeric_limits<float>::infinity();
    Vec3f best_vertex{};
    float value() const { return std::max(best, skipped); }
    void offer(Vec3f d, Vec3f vertex) {
        const float projection = project(d, vertex);
        if (projection > best) {
            best = projection;
            best_vertex = vertex;
        }
    }
};

/// The bounds of `node`'s children along `d` (box_bound of each used slot; -infinity for
/// unused ones) into `bounds`. Reads the node's planes by the sign of each component, so a
/// slot costs three multiply-adds and no branch.
void child_bounds_along(const WideNode& node, Vec3f d, int count, float* bounds) {
#ifdef __AVX2__
    const float* bx = d.x > 0.0f ? node.upper_x : node.lower_x;
    const float* by = d.y > 0.0f ? node.upper_y : node.lower_y;
    const float* bz = d.z > 0.0f ? node.upper_z : node.lower_z;
    // Summed as sum_of_products does (AVX2 builds have FMA), so box_bound gives the same bits.
    const __m256 sum =
        _mm256_fmadd_ps(_mm256_set1_ps(d.z), _mm256_load_ps(bz),
                        _mm256_fmadd_ps(_mm256_set1_ps(d.x), _mm256_load_ps(bx),
                                        _mm256_mul_ps(_mm256_set1_ps(d.y), _mm256_load_ps(by))));
    // Unused slots hold infinities (and 0 * inf is NaN): they become -infinity.
    const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const __m256 used = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(count), lanes));
    _mm256_store_ps(bounds, _mm256_blendv_ps(_mm256_set1_ps(-kInfinity), sum, used));
#else
    for (int c = 0; c < kBvhWidth; ++c)
        bounds[c] = c < count ? box_bound(node.child_bounds(c), d) : -kInfinity;
#endif
}

/// The slot of the largest of `bounds` among the slots set in `live` (not empty); the lowest
/// such slot on ties.
int largest_live(const float* bounds, unsigned live) {
    int best = std::countr_zero(live);
    for (unsigned rest = live & (live - 1); rest != 0; rest &= rest - 1) {
        const int c = std::countr_zero(rest);
        if (bounds[c] > bounds[best]) best = c;
    }
    return best;
}

/// The slots among `live` whose bound exceeds `limit`: the children still worth a visit.
unsigned above(const float* bounds, unsigned live, float limit) {
#ifdef __AVX2__
    const __m256 greater = _mm256_cmp_ps(_mm256_load_ps(bounds), _mm256_set1_ps(limit), _CMP_GT_OQ);
    return live & unsigned(_mm256_movemask_ps(greater));
#else
    unsigned result = 0;
    for (unsigned rest = live; rest != 0; rest &= rest - 1) {
        const int c = std::countr_zero(rest);
        if (bounds[c] > limit) result |= 1u << c;
    }
    return result;
#endif
}

#ifdef __AVX2__
/// Raises `support` over the corners of the whole leaf `leaf` (not part of one) from its
/// pre-arranged rows (leaf_rows.h; `rows` past the padding), eight triangles at a time. The
/// projections are summed as sum_of_products does and the vertex kept is the first of the
/// largest in offer order, so the result is offer's, bit for bit.
void raise_support_from_rows(const float* rows, NodeRef leaf, Vec3f d, Support& support) {
    const std::uint32_t first = leaf.first_prim(), count = leaf.prim_count();
    const float* leaf_rows = leaf_rows_at(rows, first);
    const __m256 dx = _mm256_set1_ps(d.x), dy = _mm256_set1_ps(d.y), dz = _mm256_set1_ps(d.z);
    const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    for (std::uint32_t base = 0; base < count; base += kBvhWidth) {
        // Loads past the leaf read the next rows or the buffer's padding: masked off.
        const __m256 used =
            _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(int(count - base)), lanes));
        __m256 projections[3];
        for (int c = 0; c < 3; ++c) {
            const float* row = leaf_rows + std::size_t(3 * c) * count + base;
            const __m256 x = _mm256_loadu_ps(row), y = _mm256_loadu_ps(row + count),
                         z = _mm256_loadu_ps(row + 2 * count);
            projections[c] = _mm256_blendv_ps(
                _mm256_set1_ps(-kInfinity),
                _mm256_fmadd_ps(dz, z, _mm256_fmadd_ps(dx, x, _mm256_mul_ps(dy, y))), used);
        }
        __m256 largest =
            _mm256_max_ps(_mm256_max_ps(projections[0], projections[1]), projections[2]);
        largest = _mm256_max_ps(largest, _mm256_permute2f128_ps(largest, largest, 1));
        largest = _mm256_max_ps(largest, _mm256_shuffle_ps(largest, largest, 0b01001110));
        largest = _mm256_max_ps(largest, _mm256_shuffle_ps(largest, largest, 0b10110001));
        const float value = _mm256_cvtss_f32(largest);
        if (!(value > support.best)) continue;
        unsigned at[3];
        for (int c = 0; c < 3; ++c)
            at[c] =
                unsigned(_mm256_movemask_ps(_mm256_cmp_ps(projections[c], largest, _CMP_EQ_OQ)));
        const int lane = std::countr_zero(at[0] | at[1] | at[2]);
        const int corner = (at[0] >> lane) & 1u ? 0 : ((at[1] >> lane) & 1u ? 1 : 2);
        const float* row = leaf_rows + std::size_t(3 * corner) * count + base + lane;
        support.best = value;
        support.best_vertex = {row[0], row[count], row[2 * count]};
    }
}
#endif

/// Raises `support` over the vertices of the triangles under `ref` along `d`, skipping
/// subtrees that cannot beat it by more than `slack`. Children are taken in the order of
/// their bounds, largest first: its vertices raise the best early and prune the siblings.
/// Recursion depth is the object BVH's depth; no allocation.
void raise_support(const ObjectBvh& bvh, NodeRef ref, Vec3f d, float slack, Support& support) {
    if (ref.is_empty()) return;
    if (ref.is_leaf()) {
        const std::uint32_t first = ref.first_prim();
        for (std::uint32_t i = first; i < first + ref.prim_count(); ++i) {
            const TriangleVerts& t = bvh.triangles[i];
            support.offer(d, t.v0);
            support.offer(d, t.v1);
            support.offer(d, t.v2);
        }
        return;
    }
    const WideNode& node = bvh.nodes[ref.node_id()];
    const int count = node.child_count();
    alignas(32) float bounds[kBvhWidth];
    child_bounds_along(node, d, count, bounds);
    // Children in the order of their bounds, largest first, while one can still beat the best
    // by more than the slack: each visit may raise the best, so the test is made again after
    // it, on the children not yet visited (usually one or two are left).
    unsigned live = (1u << count) - 1;
    for (unsigned worth = above(bounds, live, support.best + slack); worth != 0;
         worth = above(bounds, live, support.best + slack)) {
        const int c = largest_live(bounds, worth);
        live &= ~(1u << c);
#ifdef __AVX2__
        if (node.children[c].is_leaf() && !bvh.leaf_rows.empty()) {
            raise_support_from_rows(bvh.leaf_rows.data() + kLeafRowPadding, node.children[c], d,
                                    support);
            continue;
        }
#endif
        raise_support(bvh, node.children[c], d, slack, support);
    }
    // The children left are within the slack of the best (or below it, where counting them
    // changes nothing): the largest of their bounds stands for them.
    if (live != 0) support.skipped = std::max(support.skipped, bounds[largest_live(bounds, live)]);
}

float max_abs(Vec3f v) {
    return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
}

}  // namespace

VertexSupport vertex_support(const ObjectBvh& bvh, NodeRef node, Vec3f direction, float slack,
                             const Vec3f* start) {
    Support support;
    if (start) support.offer(direction, *start);
    raise_support(bvh, node, direction, slack, support);
    return {support.value(), support.best_vertex};
}

BBox3f vertex_world_bounds(const ObjectBvh& bvh, NodeRef node, const BBox3f& node_box,
                           const AffineTransform& to_world, float tolerance) {
    if (node.is_empty() || node_box.is_empty()) return BBox3f{};
    BBox3f box;
    for (int axis = 0; axis < 3; ++axis) {
        const Vec3f row{to_world.col_x[axis], to_world.col_y[axis], to_world.col_z[axis]};
        // The node's extent along the row bounds how far off a skipped subtree may be.
        const float slack = tolerance * (box_bound(node_box, row) + box_bound(node_box, -row));
        Support highest, lowest_negated;
        raise_support(bvh, node, row, slack, highest);
        raise_support(bvh, node, -row, slack, lowest_negated);
        box.min[axis] = -lowest_negated.value() + to_world.translation[axis];
        box.max[axis] = highest.value() + to_world.translation[axis];
    }
    // The projections and the sums above round: 8 ulps, like transformed leaf bounds
    // (bref_bounds.cpp).
    return widen_for_mapping_rounding(box, to_world,
                                      std::max(max_abs(node_box.min), max_abs(node_box.max)), 8.0f);
}

BBox3f widen_for_mapping_rounding(BBox3f box, const AffineTransform& to_world,
                                  float object_magnitude, float ulps) {
    const float matrix_magnitude =
        std::max({max_abs(to_world.col_x), max_abs(to_world.col_y), max_abs(to_world.col_z)});
    const float magnitude =
        std::max({3.0f * matrix_magnitude * object_magnitude, max_abs(to_world.translation),
                  max_abs(box.min), max_abs(box.max)});
    const float pad = magnitude * ulps * 0x1p-23f;
    box.min = box.min - Vec3f{pad, pad, pad};
    box.max = box.max + Vec3f{pad, pad, pad};
    return box;
}

}  // namespace rebraid
