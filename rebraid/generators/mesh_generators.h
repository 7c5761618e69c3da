#pragma once

#include <cstdint>

#include "rebraid/core/scene.h"

namespace rebraid {

/// Procedural meshes for the default scene and scene generators. All are Y-up (glTF's
/// convention), closed or open triangle surfaces with outward winding (counter-clockwise seen
/// from outside), deterministic for their settings, and centred on the origin unless a
/// setting says otherwise. Every settings field is clamped to its minimum where noted, so
/// any settings give a valid mesh.

/// Sphere from latitude rings and longitude segments; shared vertices at the poles.
/// Triangles: 2 * segment_count * (ring_count - 1).
struct UvSphereSettings {
    float radius = 1.0f;               ///< world units
    std::uint32_t segment_count = 48;  ///< around the Y axis; at least 3
    std::uint32_t ring_count = 32;     ///< pole to pole; at least 2
};
Mesh make_uv_sphere(const UvSphereSettings& settings = {});

/// Torus around the Y axis (lying in the XZ plane). Triangles: 2 * major * minor segments.
struct TorusSettings {
    float major_radius = 1.0f;               ///< centre of the tube to the Y axis
    float minor_radius = 0.25f;              ///< tube radius
    std::uint32_t major_segment_count = 64;  ///< around the Y axis; at least 3
    std::uint32_t minor_segment_count = 24;  ///< around the tube; at least 3
};
Mesh make_torus(const TorusSettings& settings = {});

/// Axis-aligned box with the given half extents (12 triangles).
Mesh make_box(Vec3f half_extents = {1.0f, 1.0f, 1.0f});

/// Ground: a grid in the XZ plane, centred on the origin, with low-frequency dips below
/// y = 0 (never above, so objects placed at y = 0 rest on or just above it).
/// Triangles: 2 * cell_count^2.
struct GroundGridSettings {
    float size = 40.0f;              ///< edge length along X and Z
    std::uint32_t cell_count = 128;  ///< cells per edge; at least 1
    float dip_depth = 0.15f;         ///< deepest dip below y = 0; 0 = flat
    std::uint64_t seed = 1;          ///< phases of the dips
};
Mesh make_ground_grid(const GroundGridSettings& settings = {});

/// A stylised tree standing on y = 0: a capped cylindrical trunk and a lumpy canopy (a
/// sphere displaced by a few seeded waves) on top of it.
struct TreeSettings {
    float trunk_radius = 0.15f;
    float trunk_height = 1.6f;
    std::uint32_t trunk_segment_count = 16;  ///< around the trunk; at least 3
    float canopy_radius = 1.0f;
    float canopy_lumpiness = 0.2f;            ///< displacement relative to canopy_radius
    std::uint32_t canopy_segment_count = 40;  ///< at least 3
    std::uint32_t canopy_ring_count = 24;     ///< at least 2
    std::uint64_t seed = 7;                   ///< shape of the lumps
};
Mesh make_tree(const TreeSettings& settings = {});

/// A tube along a (p, q) torus knot around the Y axis (p = 2, q = 3 is the trefoil). The
/// tube is closed along the knot, so it has no seam or caps.
/// Triangles: 2 * path_segment_count * tube_segment_count.
struct TorusKnotSettings {
    std::uint32_t p = 2;         ///< turns around the Y axis; at least 1
    std::uint32_t q = 3;         ///< turns through the torus hole; at least 1
    float major_radius = 1.0f;   ///< radius of the underlying torus
    float minor_radius = 0.45f;  ///< how far the knot winds from that torus' core
    float tube_radius = 0.15f;
    std::uint32_t path_segment_count = 256;  ///< along the knot; at least 3
    std::uint32_t tube_segment_count = 12;   ///< around the tube; at least 3
};
Mesh make_torus_knot(const TorusKnotSettings& settings = {});

/// An open tube wound as a helical spring rising along +Y from y = 0 to `height`.
/// Triangles: 2 * path_segment_count * tube_segment_count.
struct HelixSettings {
    float coil_radius = 0.3f;  ///< helix axis to tube centre
    float height = 6.0f;
    float turn_count = 8.0f;
    float tube_radius = 0.08f;
    std::uint32_t path_segment_count = 320;  ///< along the helix; at least 1
    std::uint32_t tube_segment_count = 10;   ///< around the tube; at least 3
};
Mesh make_helix(const HelixSettings& settings = {});

}  // namespace rebraid
