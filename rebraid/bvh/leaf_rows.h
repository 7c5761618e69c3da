#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/triangle.h"
#include "rebraid/core/types.h"

namespace rebraid {

/// Floats of padding before and after the leaf rows: a SIMD load of a leaf's row may start
/// up to this many floats before the leaf and run as far past it.
inline constexpr std::uint32_t kLeafRowPadding = 8;

/// Rows of corners: 3 corners by 3 axes.
inline constexpr std::uint32_t kCornerRows = 9;

/// Floats of rows per triangle: the corner rows, then the triangle's primID (its bits).
inline constexpr std::uint32_t kRowFloatsPerTriangle = kCornerRows + 1;

/// The rows of the leaf whose triangles start at leaf-order position `first` (`rows` past the
/// leading padding); row r of a leaf of n triangles starts n * r floats further.
inline const float* leaf_rows_at(const float* rows, std::uint32_t first) {
    return rows + std::size_t(kRowFloatsPerTriangle) * first;
}

/// The corners of the triangle whose rows start at `first` (leaf_rows_at of its leaf plus its
/// place in the leaf; each row `stride` floats, the leaf's triangle count), read back.
inline TriangleVerts leaf_row_corners(const float* first, std::uint32_t stride) {
    static_assert(sizeof(TriangleVerts) == kCornerRows * sizeof(float));
    TriangleVerts out;
    float* values = &out.v0.x;
    for (std::uint32_t r = 0; r < kCornerRows; ++r) values[r] = first[std::size_t(r) * stride];
    return out;
}

/// The primID of that triangle, from its leaf's id row.
inline PrimId leaf_row_prim_id(const float* first, std::uint32_t stride) {
    return std::bit_cast<PrimId>(first[std::size_t(kCornerRows) * stride]);
}

/// Leaf rows of at least this many bytes in a structure (all its object BVHs together) are
/// asked for ahead by the closest-hit traversal (LeafRowsPrefetch, leaf_row_hints.h); fewer
/// are left to the caches, which hold them anyway, so that asking costs more than it hides.
/// Without the requests the flat BVH traced chinese_dragon's primary rays 1.023x as fast, the
/// re-braided structures of brainstem, cg57_cruiser, the default scene and the generated
/// trees and city (up to 7.2 MB of rows) 1.00-1.014x; with them the flat BVH traced the default
/// scene's diffuse rays (59 MB of rows) 1.09x and the generated powerplant's 1.06x as fast
/// (bench/tools/kernel_ab.py on an AMD EPYC of family 25, 32 MB of L3; docs/design.md,
/// "Leaves").
inline constexpr std::uint64_t kLeafRowPrefetchMinBytes = std::uint64_t(16) << 20;

/// Whether a structure whose object BVHs hold `row_floats` floats of leaf rows in all asks
/// for them ahead (kLeafRowPrefetchMinBytes).
inline bool prefetches_leaf_rows(std::uint64_t row_floats) {
    return row_floats * sizeof(float) >= kLeafRowPrefetchMinBytes;
}

/// The corners of every leaf's triangles stored pre-arranged for the SIMD group test: the
/// leaf at leaf-order positions [p, p + n) holds 10 rows of n floats at floats [10p, 10p + 10n)
/// (after the leading padding), row 3c + a holding axis a of corner c of the leaf's
/// triangles in order, row 9 their primIDs (the PrimId's bits). A test then loads each row
/// straight into its lanes instead of transposing three corners per triangle, and a hit's
/// primID is read from the leaf just tested: from an array of its own it was a cache miss
/// per hit on scenes larger than the caches (as Embree keeps ids in its triangle leaves).
/// Built from `triangles` and `prim_ids` (leaf order) and the leaves of `nodes` below `root`.
std::vector<float> make_leaf_rows(const std::vector<WideNode>& nodes, NodeRef root,
                                  const std::vector<TriangleVerts>& triangles,
                                  const std::vector<PrimId>& prim_ids);

/// Writes the rows of every leaf below `root` again, in place (the buffer keeps its address,
/// which traversal views point into): after an update changed corners or regrouped leaves.
/// `rows` must hold as many floats as make_leaf_rows made for these triangles.
void rewrite_leaf_rows(const std::vector<WideNode>& nodes, NodeRef root,
                       const std::vector<TriangleVerts>& triangles,
                       const std::vector<PrimId>& prim_ids, std::vector<float>& rows);

/// Writes only the id row of every leaf below `root` again, from `ids` (leaf order): a
/// structure that names its hits otherwise than by mesh primID (flat_hit_ids.h).
void rewrite_leaf_row_ids(const std::vector<WideNode>& nodes, NodeRef root,
                          const std::vector<std::uint32_t>& ids, std::vector<float>& rows);

/// Writes the rows of one leaf again from `triangles` and `prim_ids` (leaf order) into `rows`
/// (the whole buffer, padding included).
void write_leaf_rows(NodeRef leaf, const TriangleVerts* triangles, const PrimId* prim_ids,
                     float* rows);

}  // namespace rebraid
