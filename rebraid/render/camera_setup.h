#pragma once

#include <optional>
#include <span>
#include <string>

#include "rebraid/core/scene.h"
#include "rebraid/io/gltf_camera.h"
#include "rebraid/render/camera.h"

namespace rebraid::viewer {

/// What the user asked of the camera (`--camera`, `--look-from`, `--look-at`, `--fov`).
struct CameraRequest {
    /// glTF camera index (`cameras[N]`); none = the file's lowest-numbered placed camera.
    std::optional<std::uint32_t> gltf_camera_id;
    std::optional<Vec3f> look_from;
    std::optional<Vec3f> look_at;
    /// Vertical field of view in degrees, in (0, 180).
    std::optional<float> fov_y_degrees;
    /// The scene's vertical; glTF's is +Y.
    Vec3f world_up{0.0f, 1.0f, 0.0f};
};

/// The chosen camera and where it came from.
struct CameraChoice {
    Camera camera;
    std::string description;  ///< e.g. "glTF camera 0 ('Camera')" or "auto-framed"
};

/// Picks the camera of `rebraid render`:
/// 1. the requested glTF camera, else the file's first (lowest-numbered) camera placed by a
///    node of the scene, else a camera auto-framed on the scene (frame_scene());
/// 2. `--look-from` / `--look-at` then replace its position / target (a missing one keeps the
///    camera's position, or aims at the scene's centre), giving a perspective camera;
/// 3. `--fov` replaces the vertical field of view (auto-framing fits the scene with it).
/// The image aspect always comes from the image size. Throws rebraid::Error for a requested
/// glTF camera the file does not place (listing the ones it does), or a degenerate view.
CameraChoice choose_camera(const Scene& scene, std::span<const GltfCamera> gltf_cameras,
                           const CameraRequest& request, float aspect);

/// The viewer's camera looking like `gltf_camera` (its field of view or orthographic size).
Camera camera_from_gltf(const GltfCamera& gltf_camera);

}  // namespace rebraid::viewer
