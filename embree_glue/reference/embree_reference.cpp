#include "embree_glue/reference/embree_reference.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <memory>
#include <string>
#include <type_traits>

#include "embree_glue/reference/embree_geometry.h"
#include "rebraid/core/error.h"

namespace rebraid::glue {
namespace {

/// Drops our reference to a geometry; a scene it is attached to holds its own.
struct GeometryReleaser {
    void operator()(RTCGeometry geometry) const { rtcReleaseGeometry(geometry); }
};
using GeometryReference = std::unique_ptr<std::remove_pointer_t<RTCGeometry>, GeometryReleaser>;

GeometryReference new_geometry(EmbreeDevice& device, RTCGeometryType type) {
    GeometryReference geometry(rtcNewGeometry(device.get(), type));
    device.throw_if_error("rtcNewGeometry");
    if (!geometry) throw Error("rtcNewGeometry: Embree returned no geometry");
    return geometry;
}

void configure_scene(EmbreeDevice& device, RTCScene scene,
                     const EmbreeReferenceSettings& settings) {
    rtcSetSceneFlags(scene, settings.is_robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    device.throw_if_error("rtcSetSceneFlags");
    rtcSetSceneBuildQuality(scene, to_embree_quality(settings.build_quality));
    device.throw_if_error("rtcSetSceneBuildQuality");
}

void commit_scene(EmbreeDevice& device, RTCScene scene) {
    rtcCommitScene(scene);
    device.throw_if_error("rtcCommitScene");
}

/// What happens to a ray before it may reach Embree.
enum class RayCheck { trace, empty_segment };

/// The error for a ray check_ray does not pass: tnear negative, or a coordinate beyond
/// `limits` or not finite. Out of line: no valid ray pays for the messages.
[[gnu::cold, gnu::noinline]] void throw_invalid_ray(const Ray& ray, const EmbreeRayLimits& limits,
                                                    const char* accel_name) {
    if (!(ray.tnear >= 0.0f))
        throw Error(std::string(accel_name) + ": ray tnear " + std::to_string(ray.tnear) +
                    " is negative; Embree only traces segments with tnear >= 0");
    for (int axis = 0; axis < 3; ++axis) {
        if (!(std::fabs(ray.org[axis]) <= limits.max_origin_coordinate))
            throw Error(std::string(accel_name) + ": ray origin coordinate " +
                        std::to_string(ray.org[axis]) + " is not finite or beyond " +
                        std::to_string(limits.max_origin_coordinate) +
                        ", the largest Embree can trace in this scene");
        if (!(std::fabs(ray.dir[axis]) <= limits.max_direction_coordinate))
            throw Error(std::string(accel_name) + ": ray direction coordinate " +
                        std::to_string(ray.dir[axis]) + " is not finite or beyond " +
                        std::to_string(limits.max_direction_coordinate) +
                        ", the largest Embree can trace in this scene");
    }
}

/// Checks what Embree's single-ray kernels assert on (Debian's build keeps the assertions,
/// so an invalid ray would abort the whole process). `accel_name` names the caller in errors.
/// Every benchmarked Embree query passes here, so the valid case is one branch over
/// comparisons that are all true (NaN compares false and takes the error path).
RayCheck check_ray(const Ray& ray, const EmbreeRayLimits& limits, const char* accel_name) {
    // No t satisfies tnear <= t <= tfar (this also catches NaN bounds): a miss by contract.
    // Embree itself treats tnear > tfar as an inactive ray, but not NaN.
    if (!(ray.tnear <= ray.tfar)) return RayCheck::empty_segment;
    const float org = limits.max_origin_coordinate, dir = limits.max_direction_coordinate;
    // Every comparison made, then one branch: `&` on their 0/1 values, not `&&`.
    const int is_valid = int(ray.tnear >= 0.0f) & int(std::fabs(ray.org.x) <= org) &
                         int(std::fabs(ray.org.y) <= org) & int(std::fabs(ray.org.z) <= org) &
                         int(std::fabs(ray.dir.x) <= dir) & int(std::fabs(ray.dir.y) <= dir) &
                         int(std::fabs(ray.dir.z) <= dir);
    if (!is_valid) throw_invalid_ray(ray, limits, accel_name);
    return RayCheck::trace;
}

/// Limits for world-space rays such that every instance's object-space image of the ray still
/// passes Embree's check. With L the inverse linear part and t the translation, the image of
/// an origin o is L (o - t), bounded by |L|_inf (|o|_inf + |t|_inf) per coordinate.
EmbreeRayLimits instanced_ray_limits(const Scene& scene) {
    EmbreeRayLimits limits;
    for (std::size_t i = 0; i < scene.instances.size(); ++i) {
        const AffineTransform& to_world = scene.instances[i].object_to_world;
        const AffineTransform to_object = to_world.inverse();
        float norm = 0.0f;  // infinity norm: largest row sum of absolute entries
        for (int row = 0; row < 3; ++row)
            norm =
                std::max(norm, std::fabs(to_object.col_x[row]) + std::fabs(to_object.col_y[row]) +
                                   std::fabs(to_object.col_z[row]));
        if (!to_object.is_finite() || !std::isfinite(norm) || norm <= 0.0f)
            throw Error("EmbreeInstancedAccel: instance " + std::to_string(i) +
                        " has a transform whose inverse is not finite in float (determinant " +
                        std::to_string(to_world.determinant()) + ")");
        const float largest_translation =
            std::max({std::fabs(to_world.translation.x), std::fabs(to_world.translation.y),
                      std::fabs(to_world.translation.z)});
        limits.max_direction_coordinate =
            std::min(limits.max_direction_coordinate, kEmbreeLargestRayCoordinate / norm);
        limits.max_origin_coordinate = std::min(
            limits.max_origin_coordinate, kEmbreeLargestRayCoordinate / norm - largest_translation);
    }
    return limits;
}

/// Which Embree id names the instance in a hit.
enum class InstanceIdSource { geom_id, inst_id };

Hit intersect_scene(RTCScene scene, const Ray& ray, InstanceIdSource source,
                    const EmbreeRayLimits& limits, const char* accel_name) {
    if (check_ray(ray, limits, accel_name) == RayCheck::empty_segment) return Hit{};
    return embree_closest_hit(scene, ray, source == InstanceIdSource::inst_id);
}

bool occluded_scene(RTCScene scene, const Ray& ray, const EmbreeRayLimits& limits,
                    const char* accel_name) {
    // The segment check rules out an input tfar of -inf, Embree's mark of an occluded ray.
    if (check_ray(ray, limits, accel_name) == RayCheck::empty_segment) return false;
    return embree_is_occluded(scene, ray);
}

void validate_input(const Scene& scene, const char* accel_name) {
    try {
        scene.validate();
    } catch (const Error& error) {
        throw Error(std::string(accel_name) + ": " + error.what());
    }
}

/// Counts shared by both structures; build time and memory are filled in after the build.
/// Validates first: counting follows instance -> mesh ids, which an invalid scene may have
/// out of range (the constructors call this before their bodies run).
AccelStats validated_input_stats(const Scene& scene, const char* accel_name) {
    validate_input(scene, accel_name);
    AccelStats stats;
    stats.triangles = scene.instanced_triangle_count();
    stats.instances = scene.instances.size();
    stats.meshes = scene.meshes.size();
    return stats;
}

double milliseconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
}

}  // namespace

bool is_traced_by_embree(const Ray& ray, const EmbreeRayLimits& limits, const char* accel_name) {
    return check_ray(ray, limits, accel_name) == RayCheck::trace;
}

// ---- EmbreeFlatAccel ---------------------------------------------------------------------

EmbreeFlatAccel::EmbreeFlatAccel(const Scene& scene, const EmbreeReferenceSettings& settings)
    : device_(settings.device_config),
      scene_(device_),
      stats_(validated_input_stats(scene, "EmbreeFlatAccel")) {
    const auto start = std::chrono::steady_clock::now();
    configure_scene(device_, scene_.get(), settings);
    // One geometry per instance rather than one big geometry plus a prim -> (instance, prim)
    // table: geomID is then the instance id and primID the mesh's own triangle index.
    for (std::size_t i = 0; i < scene.instances.size(); ++i) {
        const Instance& instance = scene.instances[i];
        const Mesh& mesh = scene.meshes[instance.mesh_id];
        if (mesh.triangles.empty()) continue;  // nothing to hit: no geometry, the id stays unused
        try {
            attach_triangle_mesh(device_, scene_.get(), mesh, &instance.object_to_world,
                                 static_cast<unsigned int>(i),
                                 to_embree_quality(settings.build_quality));
        } catch (const Error& error) {
            throw Error("EmbreeFlatAccel: instance " + std::to_string(i) + " (mesh " +
                        std::to_string(instance.mesh_id) + "): " + error.what());
        }
    }
    try {
        commit_scene(device_, scene_.get());
    } catch (const Error& error) {
        throw Error(std::string("EmbreeFlatAccel: ") + error.what());
    }
    stats_.build_ms = milliseconds_since(start);
    stats_.memory_bytes =
        static_cast<std::uint64_t>(std::max<std::int64_t>(device_.allocated_bytes(), 0));
}

Hit EmbreeFlatAccel::intersect_counted(const Ray& ray, TraversalCounters* /*counters*/) const {
    return intersect_scene(scene_.get(), ray, InstanceIdSource::geom_id, EmbreeRayLimits{},
                           "EmbreeFlatAccel");
}

bool EmbreeFlatAccel::occluded(const Ray& ray) const {
    return occluded_scene(scene_.get(), ray, EmbreeRayLimits{}, "EmbreeFlatAccel");
}

AccelStats EmbreeFlatAccel::stats() const {
    return stats_;
}

// ---- EmbreeInstancedAccel ----------------------------------------------------------------

EmbreeInstancedAccel::EmbreeInstancedAccel(const Scene& scene,
                                           const EmbreeReferenceSettings& settings)
    : device_(settings.device_config),
      top_scene_(device_),
      stats_(validated_input_stats(scene, "EmbreeInstancedAccel")) {
    ray_limits_ = instanced_ray_limits(scene);
    const auto start = std::chrono::steady_clock::now();

    // Object level: one committed scene per mesh, geometry 0 in object space. A mesh without
    // triangles gets an empty scene, which instances may reference harmlessly.
    mesh_scenes_.reserve(scene.meshes.size());
    for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
        const Mesh& mesh = scene.meshes[m];
        try {
            EmbreeSceneHandle& mesh_scene = mesh_scenes_.emplace_back(device_);
            configure_scene(device_, mesh_scene.get(), settings);
            if (!mesh.triangles.empty())
                attach_triangle_mesh(device_, mesh_scene.get(), mesh, nullptr, 0,
                                     to_embree_quality(settings.build_quality));
            commit_scene(device_, mesh_scene.get());
        } catch (const Error& error) {
            throw Error("EmbreeInstancedAccel: mesh " + std::to_string(m) + " ('" + mesh.name +
                        "'): " + error.what());
        }
    }

    // Top level: instance i is geometry i, so Embree reports it in instID[0].
    configure_scene(device_, top_scene_.get(), settings);
    for (std::size_t i = 0; i < scene.instances.size(); ++i) {
        const Instance& instance = scene.instances[i];
        try {
            GeometryReference geometry = new_geometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(geometry.get(), mesh_scenes_[instance.mesh_id].get());
            device_.throw_if_error("rtcSetGeometryInstancedScene");
            // AffineTransform is laid out as RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR (checked above).
            rtcSetGeometryTransform(geometry.get(), 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR,
                                    &instance.object_to_world);
            device_.throw_if_error("rtcSetGeometryTransform");
            rtcCommitGeometry(geometry.get());
            device_.throw_if_error("rtcCommitGeometry(instance)");
            rtcAttachGeometryByID(top_scene_.get(), geometry.get(), static_cast<unsigned int>(i));
            device_.throw_if_error("rtcAttachGeometryByID(instance)");
        } catch (const Error& error) {
            throw Error("EmbreeInstancedAccel: instance " + std::to_string(i) + " (mesh " +
                        std::to_string(instance.mesh_id) + "): " + error.what());
        }
    }
    try {
        commit_scene(device_, top_scene_.get());
    } catch (const Error& error) {
        throw Error(std::string("EmbreeInstancedAccel: top level: ") + error.what());
    }
    stats_.build_ms = milliseconds_since(start);
    stats_.memory_bytes =
        static_cast<std::uint64_t>(std::max<std::int64_t>(device_.allocated_bytes(), 0));
}

Hit EmbreeInstancedAccel::intersect_counted(const Ray& ray, TraversalCounters* /*counters*/) const {
    return intersect_scene(top_scene_.get(), ray, InstanceIdSource::inst_id, ray_limits_,
                           "EmbreeInstancedAccel");
}

bool EmbreeInstancedAccel::occluded(const Ray& ray) const {
    return occluded_scene(top_scene_.get(), ray, ray_limits_, "EmbreeInstancedAccel");
}

AccelStats EmbreeInstancedAccel::stats() const {
    return stats_;
}

}  // namespace rebraid::glue
