#pragma once

#include <cstdint>

#include "rebraid/core/scene.h"

namespace rebraid {

/// More procedural meshes, for the scene generators (scene_generators.h): trees, jewels,
/// pipes and buildings. Same conventions as mesh_generators.h: Y-up, outward winding
/// (counter-clockwise seen from outside) on closed parts, deterministic for their settings,
/// and counts clamped to their minimum where noted, so any settings give a valid mesh.
/// Some meshes are unions of overlapping closed parts (a building is a pile of boxes): fine
/// for ray tracing, which is all the project does with them.

/// Cylinder around the Y axis from y = 0 to `height`.
/// Triangles: 2 * segment_count * length_segment_count, plus 2 * segment_count with caps.
struct CylinderSettings {
    float radius = 0.5f;                     ///< world units
    float height = 1.0f;                     ///< the cylinder spans y in [0, height]
    std::uint32_t segment_count = 24;        ///< around the axis; at least 3
    std::uint32_t length_segment_count = 1;  ///< rings along the axis; at least 1
    bool is_capped = true;                   ///< closes both ends with triangle fans
};
Mesh make_cylinder(const CylinderSettings& settings = {});

/// A broad-leaved tree standing on y = 0: a trunk that forks recursively into tapered
/// branches (open tubes), with a cluster of small square leaves (two triangles each, single
/// sheets) around every outermost branch tip. Its canopy is mostly empty space, like the
/// paper's Xfrog trees. With B = branch_count and L = level_count, triangles:
/// 2 * segment_count * (1 + B + ... + B^L) + 2 * leaf_count * B^L.
struct BranchingTreeSettings {
    float trunk_height = 1.4f;        ///< length of the trunk (level 0)
    float trunk_radius = 0.12f;       ///< at the base; branches taper by radius_ratio
    std::uint32_t level_count = 3;    ///< generations of branches above the trunk; at most 6
    std::uint32_t branch_count = 3;   ///< children per branch; 1 to 8
    float branch_angle = 0.65f;       ///< radians between a child and its parent (+-20% jitter)
    float length_ratio = 0.72f;       ///< child length / parent length (+-15% jitter)
    float radius_ratio = 0.6f;        ///< child base radius / parent base radius
    std::uint32_t segment_count = 8;  ///< around each branch; at least 3
    std::uint32_t leaf_count = 24;    ///< leaves around each outermost tip
    float leaf_size = 0.16f;          ///< edge length of a leaf
    float leaf_spread = 0.4f;         ///< leaves lie within this distance of their tip
    std::uint64_t seed = 11;          ///< branch jitter and leaf placement
};
Mesh make_branching_tree(const BranchingTreeSettings& settings = {});

/// A conifer standing on y = 0: a capped trunk and `tier_count` stacked cones ("skirts") of
/// shrinking radius, each with a jagged rim and a shallow underside, overlapping in height.
/// Triangles: 32 for the trunk + tier_count * 2 * ring_count * segment_count.
struct ConiferSettings {
    float height = 4.0f;               ///< tip above y = 0
    float trunk_radius = 0.1f;         ///< the trunk is a capped 8-sided cylinder
    float trunk_height = 0.6f;         ///< bare trunk below the lowest tier
    float base_radius = 1.1f;          ///< radius of the lowest tier
    std::uint32_t tier_count = 6;      ///< at least 1
    std::uint32_t segment_count = 40;  ///< around the axis; at least 3
    std::uint32_t ring_count = 5;      ///< rows from a tier's rim to its apex; at least 1
    float jaggedness = 0.15f;          ///< rim radius variation, relative; below 1
    std::uint64_t seed = 5;            ///< shape of the rims
};
Mesh make_conifer(const ConiferSettings& settings = {});

/// A band like a crown's or a ring's: a thick-walled tube around the Y axis from y = 0 up
/// to `height`, optionally with `crest_count` points rising from its top edge.
/// Triangles: 8 * segment_count (outer wall, top, inner wall, bottom).
struct RingBandSettings {
    float radius = 1.0f;                ///< outer radius
    float height = 0.3f;                ///< of the flat top edge (crests rise above it)
    float thickness = 0.05f;            ///< wall thickness, below radius
    std::uint32_t segment_count = 128;  ///< around the axis; at least 3
    std::uint32_t crest_count = 0;      ///< points on the top edge; 0 = flat edge
    float crest_height = 0.0f;          ///< height of the points above `height`
};
Mesh make_ring_band(const RingBandSettings& settings = {});

/// A faceted gem, table up (+Y), girdle (widest ring) at y = 0 with the given radius.
/// Triangles: 4 * facet_count (table fan, crown zigzag, pavilion fan).
struct GemSettings {
    float radius = 1.0f;             ///< of the girdle
    std::uint32_t facet_count = 16;  ///< around the axis; at least 3
    float table_ratio = 0.55f;       ///< table radius / radius
    float crown_height = 0.35f;      ///< table above the girdle, relative to radius
    float pavilion_depth = 0.85f;    ///< culet below the girdle, relative to radius
};
Mesh make_gem(const GemSettings& settings = {});

/// A steel I-beam along the X axis, centred on the origin: two flanges and a web (three
/// boxes with their long sides cut into length_segment_count slices; 3 * (8 * slices + 4)
/// triangles).
struct IBeamSettings {
    float length = 1.0f;                      ///< along X
    float width = 0.03f;                      ///< flange width (Z)
    float height = 0.045f;                    ///< total height (Y)
    float flange_thickness = 0.006f;          ///< along Y
    float web_thickness = 0.004f;             ///< along Z
    std::uint32_t length_segment_count = 32;  ///< slices along X; at least 1
};
Mesh make_i_beam(const IBeamSettings& settings = {});

/// A pipe along the X axis, centred on the origin, with `flange_count` collars spread
/// evenly from end to end. Triangles: 2 * segment_count * (length_segment_count + 1) for the
/// capped pipe, plus 4 * segment_count per flange.
struct FlangedPipeSettings {
    float length = 1.0f;                      ///< along X, end to end
    float radius = 0.0125f;                   ///< of the pipe
    std::uint32_t segment_count = 24;         ///< around the pipe; at least 3
    std::uint32_t length_segment_count = 32;  ///< rings along the pipe; at least 1
    std::uint32_t flange_count = 0;           ///< collars, evenly from end to end (one: the middle)
    float flange_radius = 0.02f;              ///< outer radius of a collar
    float flange_width = 0.006f;              ///< along X
};
Mesh make_flanged_pipe(const FlangedPipeSettings& settings = {});

/// A lattice truss along the X axis, centred on the origin: four chords (square bars) on
/// the corners of a square cross-section, braced by one diagonal bar per panel on each of
/// the four sides; mostly empty space inside its box. Chords are cut into one slice per
/// panel. Triangles: 4 * (8 * panel_count + 4) + 12 * 4 * panel_count.
struct TrussSettings {
    float length = 1.0f;             ///< along X
    float width = 0.04f;             ///< side of the square cross-section (chord centres)
    float bar_thickness = 0.004f;    ///< side of the square bars
    std::uint32_t panel_count = 16;  ///< diagonal braces per side; at least 1
};
Mesh make_truss(const TrussSettings& settings = {});

/// An office tower standing on y = 0 inside the footprint [-width/2, width/2] x
/// [-depth/2, depth/2]: `tier_count` stacked blocks set back from each other up to `height`,
/// a ledge at every floor and pilasters on every facade, and a machine room on the roof
/// (0.04 * height tall). All boxes: 12 * (tiers * (1 + floors + pilasters) + 1) triangles.
struct BuildingSettings {
    float width = 0.8f;            ///< along X
    float depth = 0.8f;            ///< along Z
    float height = 3.0f;           ///< of the top tier's roof
    std::uint32_t tier_count = 3;  ///< at least 1
    float setback = 0.12f;         ///< each tier's footprint shrinks by this fraction
    float floor_height = 0.25f;    ///< one ledge per floor; at least height / 1000
    float bay_width = 0.12f;       ///< pilaster spacing; at least max(width, depth) / 1000
    float relief = 0.015f;  ///< ledges and pilasters stand out this far; at most min(w, d) / 4
};
Mesh make_building(const BuildingSettings& settings = {});

}  // namespace rebraid
