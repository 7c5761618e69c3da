#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "rebraid/core/types.h"
#include "rebraid/io/gltf_scene.h"

namespace rebraid {

/// A glTF camera as placed in the world by a node of the loaded scene. glTF cameras look
/// along their node's -Z with +Y up; the node's scale is removed from the frame.
struct GltfCamera {
    std::uint32_t camera_id = 0;  ///< index in the glTF `cameras` array
    std::uint32_t node_id = 0;    ///< the node that places it (the first one, depth-first)
    std::string name;             ///< the camera's name, else its node's
    Vec3f position;
    Vec3f forward{0.0f, 0.0f, -1.0f};  ///< unit view direction
    Vec3f up{0.0f, 1.0f, 0.0f};        ///< unit, perpendicular to `forward`
    bool is_orthographic = false;
    float yfov_radians = 0.8f;  ///< perspective: vertical field of view
    float aspect_ratio = 0.0f;  ///< perspective: width / height, 0 when the file gives none
    float xmag = 1.0f;          ///< orthographic: half width of the view, in world units
    float ymag = 1.0f;          ///< orthographic: half height of the view, in world units
    float znear = 0.0f;
    float zfar = 0.0f;  ///< 0 = infinite
};

/// Every glTF camera that a node of the loaded scene places, one entry per camera (at its
/// first node in the depth-first order of README "Scene"), sorted by camera_id. Cameras no
/// node of the scene uses are left out. `loaded` must hold the model
/// (GltfLoadOptions::keep_model). Throws rebraid::Error naming the camera for a missing model,
/// an unknown camera type, a non-positive field of view or magnification, or a node transform
/// that leaves no view direction.
std::vector<GltfCamera> read_gltf_cameras(const GltfLoadResult& loaded);

}  // namespace rebraid
