#pragma once

#include <embree3/rtcore.h>

#include <vector>

#include "embree_glue/dropin/embree_interposer_registry.h"
#include "rebraid/core/scene.h"

namespace rebraid::glue {

/// The ids rtcIntersect1 reports for a hit on one instance of the converted scene.
struct EmbreeHitIds {
    unsigned int geom_id = RTC_INVALID_GEOMETRY_ID;  ///< the triangle geometry's id in its scene
    unsigned int inst_id = RTC_INVALID_GEOMETRY_ID;  ///< the instance's id, or invalid at top
    friend bool operator==(const EmbreeHitIds&, const EmbreeHitIds&) = default;
};

/// A registered Embree scene as the project's Scene, with the way back to Embree's ids.
///
/// Meshes are the distinct enabled triangle geometries the scene reaches (an RTCGeometry
/// attached to several scenes is one mesh), in the order first met. Instances, in ascending
/// geomID of the scene: a triangle geometry of the scene itself becomes one instance with the
/// identity transform (instID invalid); an instance geometry becomes one instance per enabled
/// triangle geometry of its scene (ascending geomID), with the instance's transform.
struct ConvertedEmbreeScene {
    Scene scene;
    std::vector<EmbreeHitIds> instance_ids;        ///< index = InstanceId
    std::vector<RTCGeometry> mesh_geometries;      ///< index = MeshId
    std::vector<RTCGeometry> instance_geometries;  ///< index = InstanceId; null at top level
    /// index = InstanceId: the scene holding the instance's triangle geometry.
    std::vector<RTCScene> triangle_scenes;
    /// True when the root scene or a scene holding triangles it traces asks Embree for
    /// robust mode (RTC_SCENE_FLAG_ROBUST): the structure then runs the watertight triangle
    /// test, as Embree's robust mode does, and the Möller test otherwise, as its default mode.
    bool is_robust = false;
};

/// Converts `snapshot`, copying vertices and indices out of the application's buffers.
/// Triangles Embree ignores (an index past the vertex buffer, a vertex that is not finite or
/// beyond Embree's largest coordinate) become degenerate triangles, which are never hit
/// either. Throws rebraid::Error naming the scene and geometry for anything Embree would trace
/// differently: a geometry that is not a triangle mesh or an instance (quads, curves, grids,
/// points, subdivision, user geometry), an instance inside an instanced scene, motion blur
/// (more than one time step), filter functions, a geometry mask other than all ones while
/// `is_ray_mask_supported`, an instanced scene never committed, a missing buffer or an
/// unexpected buffer format, a singular instance transform, and a root scene never committed
/// or changed (attach/detach) since its last rtcCommitScene.
ConvertedEmbreeScene convert_embree_scene(const RegisteredSceneSnapshot& snapshot,
                                          bool is_ray_mask_supported);

/// Embree's name for a geometry type ("RTC_GEOMETRY_TYPE_TRIANGLE", ...).
const char* embree_geometry_type_name(RTCGeometryType type);

}  // namespace rebraid::glue
