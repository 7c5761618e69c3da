#pragma once

#include <array>
#include <utility>

#include "rebraid/bvh/object_bvh.h"
#include "rebraid/bvh/wide_node.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/transform.h"

namespace rebraid {

/// World boxes of an object's placed vertices, from values computed once per object: what
/// vertex_world_bounds.h finds by six searches of the object BVH, mostly found by six table
/// lookups instead, for meshes placed many times.
///
/// The table holds, at the directions of a grid of kCells x kCells squares on each face of
/// the cube [-1,1]^3 (each square cut into two triangles), an upper bound of the support of
/// the vertices (their largest projection, relative to the object box's centre) and the
/// vertex of largest projection its search met. A
/// direction inside a grid triangle is a combination of the triangle's corners with
/// non-negative weights, and a support function is convex and positively homogeneous, so the
/// same combination of the corners' values bounds its support from above; the corners'
/// vertices projected onto it bound it from below. Where the two differ by more than the
/// tolerance (directions near an edge between far-apart extreme vertices, where the upper
/// bound is loose to first order in the grid spacing), a search of the BVH started from the
/// best corner vertex settles it, so every face is within the tolerance of the exact one.
class SupportTable {
public:
    static constexpr int kCells = 8;

    /// An empty table: no vertices.
    SupportTable() = default;
    /// The table of the vertices of the triangles under `node` of `bvh`, whose box is
    /// `node_box`; each grid value is exact to within `tolerance` of the box's extent along
    /// its direction (vertex_support's slack).
    SupportTable(const ObjectBvh& bvh, NodeRef node, const BBox3f& node_box,
                 float tolerance = 2e-3f);

    bool is_empty() const { return is_empty_; }

    /// A box holding every vertex of the table's node (which is `node` of `bvh`) mapped by
    /// `to_world` as transform_point rounds it, each face within `tolerance` of the node's
    /// extent along the face's row of the transform (plus rounding): the box of
    /// vertex_world_bounds, mostly without searching `bvh`. Empty for an empty table.
    BBox3f world_bounds(const AffineTransform& to_world, const ObjectBvh& bvh, NodeRef node,
                        float tolerance = 0.01f) const;
    /// A box holding the same vertices from the table alone, without searching: each face
    /// at the table's upper bound, within the grid's error of the exact one (looser than
    /// world_bounds near edges between far-apart extreme vertices, where world_bounds
    /// searches). Empty for an empty table.
    BBox3f table_world_bounds(const AffineTransform& to_world) const;

private:
    static constexpr int kSide = kCells + 1;
    static constexpr int kValues = 6 * kSide * kSide;

    /// Bounds of max over vertices v of direction · (v - centre): an upper one and a vertex
    /// whose projection is a lower one.
    struct SupportBounds {
        float upper;
        Vec3f vertex;
    };
    SupportBounds support_bounds(Vec3f direction) const;
    /// The upper bounds of support_bounds for `direction` and for its negation (the same
    /// values, bit for bit), without the vertices: what table_world_bounds needs, for two
    /// divisions instead of four.
    std::pair<float, float> upper_supports(Vec3f direction) const;
    /// The table's upper bound at the grid point (x, y) of `face`, x and y in [0, kCells].
    float interpolated_upper(int face, float x, float y) const;
    static int index(int face, int i, int j) { return (face * kSide + i) * kSide + j; }

    bool is_empty_ = true;
    Vec3f center_{};
    Vec3f half_extent_{};
    float object_magnitude_ = 0.0f;  ///< largest |coordinate| of the object box
    std::array<float, kValues> values_{};
    std::array<Vec3f, kValues> vertices_{};
};

}  // namespace rebraid
