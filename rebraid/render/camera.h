#pragma once

#include <span>

#include "rebraid/core/bbox.h"
#include "rebraid/core/ray.h"
#include "rebraid/core/scene.h"
#include "rebraid/core/types.h"

namespace rebraid::viewer {

/// A pinhole (or orthographic) camera. `forward`, `right` and `up` are unit vectors forming
/// a right-handed frame (right = forward x up); image x grows along `right`, image y downward.
struct Camera {
    Vec3f position;
    Vec3f forward{0.0f, 0.0f, -1.0f};
    Vec3f right{1.0f, 0.0f, 0.0f};
    Vec3f up{0.0f, 1.0f, 0.0f};
    float tan_half_fov_y = 0.41421356f;  ///< tan(vertical field of view / 2)
    /// When positive, an orthographic camera: half the view's height in world units (the
    /// width follows the image aspect); rays are parallel to `forward` and start in the plane
    /// through `position`. 0 = perspective.
    float ortho_half_height = 0.0f;

    /// The primary ray through the image point (`pixel_x`, `pixel_y`), measured in pixels
    /// from the top-left corner of a `width` x `height` image (pixel centres at +0.5).
    /// The direction is unit length, so t is a distance.
    Ray ray_through(float pixel_x, float pixel_y, int width, int height) const;
};

/// A camera at `look_from` looking at `look_at`, with `world_up` giving the vertical.
/// Throws rebraid::Error when the points coincide or the view is parallel to `world_up`.
Camera make_look_at_camera(Vec3f look_from, Vec3f look_at, Vec3f world_up, float fov_y_degrees);

/// How auto-framing places the camera around the scene.
struct CameraFraming {
    /// Vertical field of view.
    float fov_y_degrees = 40.0f;
    /// Direction to look from, as seen from the scene's centre: turn about `world_up` ...
    float azimuth_degrees = 35.0f;
    /// ... and height above the horizon (positive = looking down on the scene).
    float elevation_degrees = 30.0f;
    /// The vertical of the scene; glTF's is +Y.
    Vec3f world_up{0.0f, 1.0f, 0.0f};
    /// Extra room around the scene, as a factor on the fitted distance (1 = touching).
    float margin = 1.08f;
};

/// A camera looking from the framing's direction, placed so that every point is inside an
/// image of aspect `width / height`, roughly centred, and as close as that allows.
/// Throws rebraid::Error when there are no points or the aspect is not positive.
Camera frame_points(std::span<const Vec3f> points, float aspect, const CameraFraming& framing = {});

/// frame_points() on the eight corners of `bounds`; throws for an empty box.
Camera frame_bounds(const BBox3f& bounds, float aspect, const CameraFraming& framing = {});

/// frame_points() on the corners of every instance's world bounds: tighter than the scene
/// box when the scene's content does not fill the box's corners. Throws for a scene without
/// any triangles.
Camera frame_scene(const Scene& scene, float aspect, const CameraFraming& framing = {});

}  // namespace rebraid::viewer
