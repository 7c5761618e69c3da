#pragma once

#include <cstdint>

#include "rebraid/bvh/leaf_rows.h"
#include "rebraid/bvh/triangle_group.h"
#include "rebraid/core/simd_config.h"

namespace rebraid {
inline namespace REBRAID_SIMD_NAMESPACE {

#ifdef REBRAID_SIMD_AVX2

/// The triangles of sibling leaves in the lanes of shared group tests (the merged top
/// level's), from their pre-arranged rows (leaf_rows.h): each leaf's row lands in its lanes
/// with one unaligned load, shifted by its first lane and blended in, where the corner storage
/// needs a transpose per triangle. The object BVH queries, which test each leaf alone, read
/// its rows through SingleLeafRows, without these records of which leaf fills which lanes.
class LeafRowLanes {
public:
    explicit LeafRowLanes(const float* rows) : rows_(rows) {}

    /// Adds the leaf's triangles; `on_full()` is called (to test and clear the lanes)
    /// whenever all lanes are taken and more triangles remain.
    template <class OnFull>
    void add(NodeRef leaf, OnFull&& on_full) {
        const std::uint32_t first = leaf.first_prim(), count = leaf.prim_count();
        const float* base = leaf_rows_at(rows_, first);
        if (count_ + count <= kTriangleGroupSize) {  // the common case: the leaf fits
            if (count_ == 0) first_rows_ = {base, count};
            segments_[segment_count_++] = {base, count, count_, first};
            count_ += count;
            return;
        }
        for (std::uint32_t done = 0; done < count;) {
            if (count_ == kTriangleGroupSize) on_full();
            const std::uint32_t take = std::min(count - done, kTriangleGroupSize - count_);
            if (count_ == 0) first_rows_ = {base + done, count};
            segments_[segment_count_++] = {base + done, count, count_, first + done};
            count_ += take;
            done += take;
        }
    }
    std::uint32_t count() const { return count_; }
    /// The rows of the BVH's leaves (leaf_rows_at's base).
    const float* rows() const { return rows_; }
    /// The 9 corner rows of the gathered triangles (lanes past count() hold arbitrary values).
    void load_rows(__m256 (&rows)[9]) const {
        for (std::uint32_t r = 0; r < kCornerRows; ++r)
            rows[r] = _mm256_loadu_ps(first_rows_.base + std::size_t(r) * first_rows_.stride);
        for (std::uint32_t s = 1; s < segment_count_; ++s) {
            const Segment& segment = segments_[s];
            // Lanes from segment.lane on; later segments overwrite the lanes past this one.
            const __m256 lanes = _mm256_loadu_ps(kLanesFrom + 8 - segment.lane);
            const float* shifted = segment.base - segment.lane;
            for (std::uint32_t r = 0; r < kCornerRows; ++r)
                rows[r] = _mm256_blendv_ps(
                    rows[r], _mm256_loadu_ps(shifted + std::size_t(r) * segment.stride), lanes);
        }
    }
    /// The closest of the gathered triangles the ray hits within [tnear, tfar], if any, by
    /// the test `kTest` (and its terms in `terms`, when given: intersect_triangle_lanes).
    template <TriangleTest kTest>
    bool intersect(const TriangleGroupRay& ray, float tnear, float tfar, TriangleGroupHit& hit,
                   MollerTerms* terms = nullptr) const {
        __m256 rows[9];
        load_rows(rows);
        return intersect_triangle_rows<kTest>(rows, count_, ray, tnear, tfar, hit, terms);
    }
    /// Whether the ray hits any of the gathered triangles within [tnear, tfar].
    template <TriangleTest kTest>
    bool occluded(const TriangleGroupRay& ray, float tnear, float tfar) const {
        __m256 rows[9];
        load_rows(rows);
        return occluded_triangle_rows<kTest>(rows, count_, ray, tnear, tfar);
    }
    /// Leaf-order position of the triangle in `lane`.
    std::uint32_t position(std::uint32_t lane) const {
        const Segment& segment = segment_of(lane);
        return segment.position + (lane - segment.lane);
    }
    /// The rows hold each triangle's primID (prim_id()).
    static constexpr bool kHoldsPrimIds = true;
    /// PrimID of the triangle in `lane`, from its leaf's id row.
    PrimId prim_id(std::uint32_t lane) const {
        const Segment& segment = segment_of(lane);
        return leaf_row_prim_id(segment.base + (lane - segment.lane), segment.stride);
    }
    /// Corners of the triangle in `lane`, from its rows.
    TriangleVerts corners(std::uint32_t lane) const {
        const Segment& segment = segment_of(lane);
        return leaf_row_corners(segment.base + (lane - segment.lane), segment.stride);
    }
    void clear() { count_ = segment_count_ = 0; }

private:
    /// A run of one leaf's triangles: its rows from `base` (row r at base + r * stride), in
    /// lanes from `lane` on, the first at leaf-order `position`.
    struct Segment {
        const float* base;
        std::uint32_t stride, lane, position;
    };
    /// The segment whose lanes hold `lane` (the last one starting at or before it).
    const Segment& segment_of(std::uint32_t lane) const {
        std::uint32_t s = segment_count_ - 1;
        while (segments_[s].lane > lane) --s;
        return segments_[s];
    }
    /// Sign bits set from index 8 on: 8 floats read from kLanesFrom + 8 - k select lanes k..7.
    static constexpr float kLanesFrom[16] = {
        0, 0, 0, 0, 0, 0, 0, 0, -0.0f, -0.0f, -0.0f, -0.0f, -0.0f, -0.0f, -0.0f, -0.0f};
    /// The rows of the segment in lane 0, besides segments_[0]: kept in members of their own,
    /// which the compiler holds in registers, the row loads of a test wait on no reload of
    /// what add() has just stored in the segment array.
    struct FirstRows {
        const float* base;
        std::uint32_t stride;
    };
    const float* rows_;
    FirstRows first_rows_{nullptr, 0};
    Segment segments_[kTriangleGroupSize];  // left uninitialised: filled as used
    std::uint32_t count_ = 0, segment_count_ = 0;
};

#endif

}  // namespace REBRAID_SIMD_NAMESPACE
}  // namespace rebraid
