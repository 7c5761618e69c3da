#pragma once

#include <algorithm>
#include <cstdint>

#include "rebraid/bvh/hit_triangle.h"
#include "rebraid/bvh/leaf_rows.h"
#include "rebraid/bvh/triangle_group.h"
#include "rebraid/core/simd_config.h"

namespace rebraid {
inline namespace REBRAID_SIMD_NAMESPACE {

#ifdef REBRAID_SIMD_AVX2

/// One leaf's triangles in the lanes of a group test, straight from its pre-arranged rows
/// (leaf_rows.h): every query tests each leaf on its own (test_each_leaf), so the lanes need
/// no record of which leaf fills which lanes, and a test's row loads wait on nothing but the
/// leaf's reference.
class SingleLeafRows {
public:
    explicit SingleLeafRows(const float* rows) : rows_(rows) {}

    /// Calls `test()` for the leaf's triangles, 8 at a time (a leaf of more than 8 takes one
    /// test per 8).
    template <class Test>
    void test_leaf(NodeRef leaf, Test&& test) {
        const std::uint32_t first = leaf.first_prim(), count = leaf.prim_count();
        base_ = leaf_rows_at(rows_, first);
        stride_ = count;
        first_ = first;
        if (count <= kTriangleGroupSize) [[likely]] {
            count_ = count;
            test();
            return;
        }
        const float* const leaf_base = base_;
        for (std::uint32_t done = 0; done < count; done += kTriangleGroupSize) {
            base_ = leaf_base + done;
            first_ = first + done;
            count_ = std::min(count - done, kTriangleGroupSize);
            test();
        }
    }
    /// The rows of the BVH's leaves (leaf_rows_at's base).
    const float* rows() const { return rows_; }
    /// The closest of the triangles the ray hits within [tnear, tfar], if any, by the test
    /// `kTest` (and its terms in `terms`, when given: intersect_triangle_lanes).
    template <TriangleTest kTest>
    bool intersect(const TriangleGroupRay& ray, float tnear, float tfar, TriangleGroupHit& hit,
                   MollerTerms* terms = nullptr) const {
        __m256 rows[kCornerRows];
        load_rows(rows);
        return intersect_triangle_rows<kTest>(rows, count_, ray, tnear, tfar, hit, terms);
    }
    /// Whether the ray hits any of the triangles within [tnear, tfar].
    template <TriangleTest kTest>
    bool occluded(const TriangleGroupRay& ray, float tnear, float tfar) const {
        __m256 rows[kCornerRows];
        load_rows(rows);
        return occluded_triangle_rows<kTest>(rows, count_, ray, tnear, tfar);
    }
    /// Leaf-order position of the triangle in `lane`.
    std::uint32_t position(std::uint32_t lane) const { return first_ + lane; }
    /// The rows hold each triangle's primID (prim_id()).
    static constexpr bool kHoldsPrimIds = true;
    /// PrimID of the triangle in `lane`, from its leaf's id row.
    PrimId prim_id(std::uint32_t lane) const { return leaf_row_prim_id(base_ + lane, stride_); }
    /// Where the triangle in `lane` keeps its corners: its rows.
    CornerLocation corner_location(std::uint32_t lane) const {
        return {nullptr, base_ + lane, stride_};
    }

private:
    void load_rows(__m256 (&rows)[kCornerRows]) const {
        for (std::uint32_t r = 0; r < kCornerRows; ++r)
            rows[r] = _mm256_loadu_ps(base_ + std::size_t(r) * stride_);
    }

    const float* rows_;
    const float* base_ = nullptr;  // row 0 of the triangles under test; row r is r * stride_ on
    std::uint32_t stride_ = 0, first_ = 0, count_ = 0;
};

#endif

}  // namespace REBRAID_SIMD_NAMESPACE
}  // namespace rebraid
