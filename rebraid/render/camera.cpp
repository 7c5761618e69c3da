#include "rebraid/render/camera.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "rebraid/core/error.h"

namespace rebraid::viewer {

namespace {

float radians(float degrees) {
    return degrees * std::numbers::pi_v<float> / 180.0f;
}

/// Unit vector from the scene towards the camera for the framing's azimuth and elevation.
Vec3f direction_towards_camera(const CameraFraming& framing) {
    const Vec3f world_up = normalize(framing.world_up);
    const Vec3f side_reference =
        std::fabs(world_up.z) < 0.9f ? Vec3f{0.0f, 0.0f, 1.0f} : Vec3f{1.0f, 0.0f, 0.0f};
    const Vec3f horizontal_a = normalize(cross(world_up, side_reference));
    const Vec3f horizontal_b = cross(horizontal_a, world_up);
    const float azimuth = radians(framing.azimuth_degrees);
    const float elevation = radians(framing.elevation_degrees);
    return (horizontal_b * std::cos(azimuth) + horizontal_a * std::sin(azimuth)) *
               std::cos(elevation) +
           world_up * std::sin(elevation);
}

/// The smallest distance along -forward from `target` at which every point is inside the
/// view. A point at offset q from the target has depth d + q.forward and must satisfy
/// |q.right| <= depth * tan_half_x (and the same for up).
float fitting_distance(std::span<const Vec3f> points, const Camera& camera, Vec3f target,
                       float tan_half_x) {
    float distance = 0.0f;
    for (const Vec3f& p : points) {
        const Vec3f q = p - target;
        const float depth_offset = dot(q, camera.forward);
        distance = std::max(distance, std::fabs(dot(q, camera.right)) / tan_half_x - depth_offset);
        distance =
            std::max(distance, std::fabs(dot(q, camera.up)) / camera.tan_half_fov_y - depth_offset);
    }
    return distance;
}

}  // namespace

Ray Camera::ray_through(float pixel_x, float pixel_y, int width, int height) const {
    const float aspect = static_cast<float>(width) / static_cast<float>(height);
    // Map the pixel to [-1, 1] on both axes, y up.
    const float ndc_x = 2.0f * pixel_x / static_cast<float>(width) - 1.0f;
    const float ndc_y = 1.0f - 2.0f * pixel_y / static_cast<float>(height);
    if (ortho_half_height > 0.0f) {
        Ray ray;
        ray.org = position + right * (ndc_x * ortho_half_height * aspect) +
                  up * (ndc_y * ortho_half_height);
        ray.dir = forward;
        return ray;
    }
    const Vec3f dir =
        forward + right * (ndc_x * tan_half_fov_y * aspect) + up * (ndc_y * tan_half_fov_y);
    Ray ray;
    ray.org = position;
    ray.dir = normalize(dir);
    return ray;
}

Camera make_look_at_camera(Vec3f look_from, Vec3f look_at, Vec3f world_up, float fov_y_degrees) {
    const Vec3f view = look_at - look_from;
    if (!(length(view) > 0.0f))
        throw Error("the camera's look-from and look-at points are the same point");
    if (!(fov_y_degrees > 0.0f && fov_y_degrees < 180.0f))
        throw Error("camera field of view " + std::to_string(fov_y_degrees) +
                    " degrees is outside (0, 180)");
    Camera camera;
    camera.position = look_from;
    camera.forward = normalize(view);
    const Vec3f right = cross(camera.forward, world_up);
    if (!(length(right) > 1e-6f))
        throw Error("the camera's view direction is parallel to its up vector");
    camera.right = normalize(right);
    camera.up = cross(camera.right, camera.forward);
    camera.tan_half_fov_y = std::tan(radians(fov_y_degrees) * 0.5f);
    return camera;
}

Camera frame_points(std::span<const Vec3f> points, float aspect, const CameraFraming& framing) {
    if (points.empty()) throw Error("frame_points: nothing to frame");
    if (!(aspect > 0.0f))
        throw Error("frame_points: aspect " + std::to_string(aspect) + " is not positive");
    BBox3f bounds;
    for (const Vec3f& p : points) bounds.extend(p);

    // Orientation first (from unit distance), then the distance that fits every point.
    const Vec3f toward_camera = direction_towards_camera(framing);
    Camera camera = make_look_at_camera(bounds.center() + toward_camera, bounds.center(),
                                        framing.world_up, framing.fov_y_degrees);
    const float tan_half_x = camera.tan_half_fov_y * aspect;

    // Looking at the box centre leaves the content off-centre in the image (perspective, and
    // content that does not fill the box). A few rounds of "measure the points' extent in
    // the image, slide the target sideways to centre it, refit the distance" fix that.
    Vec3f target = bounds.center();
    float distance = fitting_distance(points, camera, target, tan_half_x);
    constexpr int kCentringRounds = 4;
    for (int round = 0; round < kCentringRounds && distance > 0.0f; ++round) {
        const Vec3f position = target - camera.forward * distance;
        float min_x = std::numeric_limits<float>::infinity(), max_x = -min_x;
        float min_y = min_x, max_y = -min_x;
        for (const Vec3f& p : points) {
            const Vec3f v = p - position;
            const float depth = std::max(dot(v, camera.forward), 1e-6f * distance);
            const float x = dot(v, camera.right) / depth, y = dot(v, camera.up) / depth;
            min_x = std::min(min_x, x), max_x = std::max(max_x, x);
            min_y = std::min(min_y, y), max_y = std::max(max_y, y);
        }
        // Image-plane offsets at unit depth, scaled to the target's depth.
        target = target + camera.right * (0.5f * (min_x + max_x) * distance) +
                 camera.up * (0.5f * (min_y + max_y) * distance);
        distance = fitting_distance(points, camera, target, tan_half_x);
    }

    // A point-like input still needs the camera somewhere else.
    const float size = length(bounds.extent());
    distance = std::max(distance * framing.margin, size > 0.0f ? size * 0.01f : 1.0f);
    camera.position = target - camera.forward * distance;
    return camera;
}

Camera frame_bounds(const BBox3f& bounds, float aspect, const CameraFraming& framing) {
    if (bounds.is_empty()) throw Error("frame_bounds: the bounds are empty");
    std::vector<Vec3f> corners;
    for (int corner = 0; corner < 8; ++corner)
        corners.push_back({(corner & 1) ? bounds.max.x : bounds.min.x,
                           (corner & 2) ? bounds.max.y : bounds.min.y,
                           (corner & 4) ? bounds.max.z : bounds.min.z});
    return frame_points(corners, aspect, framing);
}

Camera frame_scene(const Scene& scene, float aspect, const CameraFraming& framing) {
    std::vector<Vec3f> corners;
    corners.reserve(8 * scene.instances.size());
    for (InstanceId id = 0; id < scene.instances.size(); ++id) {
        const BBox3f box = scene.instance_bounds(id);
        if (box.is_empty()) continue;
        for (int corner = 0; corner < 8; ++corner)
            corners.push_back({(corner & 1) ? box.max.x : box.min.x,
                               (corner & 2) ? box.max.y : box.min.y,
                               (corner & 4) ? box.max.z : box.min.z});
    }
    if (corners.empty()) throw Error("the scene has no triangles for a camera to frame");
    return frame_points(corners, aspect, framing);
}

}  // namespace rebraid::viewer
