#include "rebraid/render/camera_setup.h"

#include <cmath>
#include <numbers>
#include <sstream>

#include "rebraid/core/error.h"

namespace rebraid::viewer {

namespace {

constexpr float kDefaultFovDegrees = 40.0f;

float degrees_of(float radians) {
    return radians * 180.0f / std::numbers::pi_v<float>;
}

float fov_degrees_of(const Camera& camera) {
    return camera.ortho_half_height > 0.0f ? kDefaultFovDegrees
                                           : 2.0f * degrees_of(std::atan(camera.tan_half_fov_y));
}

std::string describe(const GltfCamera& camera) {
    const std::string text = "glTF camera " + std::to_string(camera.camera_id);
    return camera.name.empty() ? text : text + " ('" + camera.name + "')";
}

const GltfCamera& find_gltf_camera(std::span<const GltfCamera> cameras, std::uint32_t id) {
    for (const GltfCamera& camera : cameras)
        if (camera.camera_id == id) return camera;
    std::string placed;
    for (const GltfCamera& camera : cameras)
        placed += (placed.empty() ? "" : ", ") + std::to_string(camera.camera_id);
    throw Error("--camera " + std::to_string(id) + ": the scene places no such glTF camera (" +
                (placed.empty() ? std::string("it has none") : "it places " + placed) + ")");
}

}  // namespace

Camera camera_from_gltf(const GltfCamera& gltf_camera) {
    Camera camera;
    camera.position = gltf_camera.position;
    camera.forward = gltf_camera.forward;
    camera.up = gltf_camera.up;
    camera.right = normalize(cross(gltf_camera.forward, gltf_camera.up));
    if (gltf_camera.is_orthographic) {
        camera.ortho_half_height = gltf_camera.ymag;
    } else {
        camera.tan_half_fov_y = std::tan(gltf_camera.yfov_radians * 0.5f);
    }
    return camera;
}

CameraChoice choose_camera(const Scene& scene, std::span<const GltfCamera> gltf_cameras,
                           const CameraRequest& request, float aspect) {
    if (request.fov_y_degrees &&
        !(*request.fov_y_degrees > 0.0f && *request.fov_y_degrees < 180.0f))
        throw Error("--fov " + std::to_string(*request.fov_y_degrees) +
                    " is outside (0, 180) degrees");
    CameraChoice choice;
    if (request.gltf_camera_id) {
        const GltfCamera& chosen = find_gltf_camera(gltf_cameras, *request.gltf_camera_id);
        choice = {camera_from_gltf(chosen), describe(chosen)};
    } else if (!gltf_cameras.empty()) {
        choice = {camera_from_gltf(gltf_cameras.front()), describe(gltf_cameras.front())};
    } else {
        CameraFraming framing;
        framing.world_up = request.world_up;
        if (request.fov_y_degrees) framing.fov_y_degrees = *request.fov_y_degrees;
        choice = {frame_scene(scene, aspect, framing), "auto-framed"};
    }

    const float fov = request.fov_y_degrees.value_or(fov_degrees_of(choice.camera));
    if (request.look_from || request.look_at) {
        const Vec3f from = request.look_from.value_or(choice.camera.position);
        const BBox3f bounds = scene.bounds();
        const Vec3f at = request.look_at.value_or(bounds.is_empty() ? Vec3f{} : bounds.center());
        // Looking straight up or down, "up" in the image is a horizontal direction instead.
        Vec3f up = request.world_up;
        if (length(cross(at - from, up)) <= 1e-6f * length(at - from) * length(up))
            up = std::fabs(up.z) < 0.9f ? Vec3f{0.0f, 0.0f, -1.0f} : Vec3f{0.0f, 1.0f, 0.0f};
        choice.camera = make_look_at_camera(from, at, up, fov);
        choice.description += ", moved by --look-from/--look-at";
    } else if (request.fov_y_degrees && choice.description != "auto-framed") {
        choice.camera.ortho_half_height = 0.0f;
        choice.camera.tan_half_fov_y =
            std::tan(*request.fov_y_degrees * std::numbers::pi_v<float> / 360.0f);
        std::ostringstream fov_text;  // "--fov 20", not "--fov 20.000000"
        fov_text << *request.fov_y_degrees;
        choice.description += ", --fov " + fov_text.str();
    }
    return choice;
}

}  // namespace rebraid::viewer
