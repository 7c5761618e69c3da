#include "embree_glue/reference/embree_dynamic_scene.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "embree_glue/reference/embree_geometry.h"
#include "rebraid/core/build_timer.h"
#include "rebraid/core/error.h"

namespace rebraid::glue {

namespace {

void configure_scene(EmbreeDevice& device, RTCScene scene, const EmbreeReferenceSettings& settings,
                     bool is_dynamic) {
    int flags = settings.is_robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE;
    if (is_dynamic) flags |= RTC_SCENE_FLAG_DYNAMIC;
    rtcSetSceneFlags(scene, static_cast<RTCSceneFlags>(flags));
    device.throw_if_error("rtcSetSceneFlags");
    rtcSetSceneBuildQuality(scene, to_embree_quality(settings.build_quality));
    device.throw_if_error("rtcSetSceneBuildQuality");
}

void commit_scene(EmbreeDevice& device, RTCScene scene, const char* what) {
    rtcCommitScene(scene);
    device.throw_if_error(what);
}

}  // namespace

std::string_view embree_dynamic_mode_name(EmbreeDynamicMode mode) {
    switch (mode) {
        case EmbreeDynamicMode::flat:
            return "embree-flat";
        case EmbreeDynamicMode::flat_refit:
            return "embree-flat-refit";
        case EmbreeDynamicMode::instanced:
            break;
    }
    return "embree-instanced";
}

EmbreeDynamicAccel::EmbreeDynamicAccel(const DynamicScene& scene, EmbreeDynamicMode mode,
                                       const EmbreeReferenceSettings& settings)
    : scene_(scene),
      mode_(mode),
      settings_(settings),
      device_(settings.device_config),
      top_scene_(device_) {
    const Scene& world = scene.scene();
    stats_.triangles = world.instanced_triangle_count();
    stats_.instances = world.instances.size();
    stats_.meshes = world.meshes.size();
    const BuildTimer timer;
    try {
        if (mode == EmbreeDynamicMode::instanced)
            build_instanced();
        else
            build_flat();
    } catch (const Error& error) {
        throw Error("EmbreeDynamicAccel (" + std::string(embree_dynamic_mode_name(mode)) +
                    "): " + error.what());
    }
    stats_.build_ms = timer.elapsed_ms();
    stats_.memory_bytes =
        static_cast<std::uint64_t>(std::max<std::int64_t>(device_.allocated_bytes(), 0));
}

void EmbreeDynamicAccel::build_flat() {
    const Scene& world = scene_.scene();
    const bool refits = mode_ == EmbreeDynamicMode::flat_refit;
    configure_scene(device_, top_scene_.get(), settings_, refits);
    std::vector<char> is_changing(world.instances.size(), 0);
    for (InstanceId id : scene_.changing_instances()) is_changing[id] = 1;
    geometries_.assign(world.instances.size(), nullptr);
    for (std::size_t i = 0; i < world.instances.size(); ++i) {
        const Instance& instance = world.instances[i];
        const Mesh& mesh = world.meshes[instance.mesh_id];
        if (mesh.triangles.empty()) continue;
        const RTCBuildQuality quality = refits && is_changing[i]
                                            ? RTC_BUILD_QUALITY_REFIT
                                            : to_embree_quality(settings_.build_quality);
        geometries_[i] =
            attach_triangle_mesh(device_, top_scene_.get(), mesh, &instance.object_to_world,
                                 static_cast<unsigned int>(i), quality);
    }
    commit_scene(device_, top_scene_.get(), "rtcCommitScene");
}

void EmbreeDynamicAccel::build_instanced() {
    const Scene& world = scene_.scene();
    geometries_.assign(world.meshes.size(), nullptr);
    mesh_scenes_.reserve(world.meshes.size());
    for (std::size_t m = 0; m < world.meshes.size(); ++m) {
        const bool is_dynamic = scene_.is_dynamic_mesh(MeshId(m));
        EmbreeSceneHandle& mesh_scene = mesh_scenes_.emplace_back(device_);
        configure_scene(device_, mesh_scene.get(), settings_, is_dynamic);
        if (!world.meshes[m].triangles.empty())
            geometries_[m] = attach_triangle_mesh(
                device_, mesh_scene.get(), world.meshes[m], nullptr, 0,
                is_dynamic ? RTC_BUILD_QUALITY_REFIT : to_embree_quality(settings_.build_quality));
        commit_scene(device_, mesh_scene.get(), "rtcCommitScene(mesh)");
    }
    configure_scene(device_, top_scene_.get(), settings_, true);
    instance_geometries_.assign(world.instances.size(), nullptr);
    for (std::size_t i = 0; i < world.instances.size(); ++i) {
        const Instance& instance = world.instances[i];
        RTCGeometry geometry = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_INSTANCE);
        device_.throw_if_error("rtcNewGeometry(instance)");
        rtcSetGeometryInstancedScene(geometry, mesh_scenes_[instance.mesh_id].get());
        rtcSetGeometryTransform(geometry, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR,
                                &instance.object_to_world);
        rtcCommitGeometry(geometry);
        rtcAttachGeometryByID(top_scene_.get(), geometry, static_cast<unsigned int>(i));
        rtcReleaseGeometry(geometry);
        device_.throw_if_error("rtcAttachGeometryByID(instance)");
        instance_geometries_[i] = geometry;
    }
    commit_scene(device_, top_scene_.get(), "rtcCommitScene(top)");
}

EmbreeFrameTimes EmbreeDynamicAccel::update() {
    EmbreeFrameTimes times;
    const Scene& world = scene_.scene();
    BuildTimer update_timer;
    if (mode_ == EmbreeDynamicMode::instanced) {
        const std::vector<MeshId>& dynamic = scene_.dynamic_meshes();
        // Meshes are independent: their buffers are rewritten and their scenes rebuilt in
        // parallel, as a renderer would.
        tbb::parallel_for(std::size_t(0), dynamic.size(), std::size_t(1), [&](std::size_t i) {
            const MeshId mesh_id = dynamic[i];
            RTCGeometry geometry = geometries_[mesh_id];
            if (geometry == nullptr) return;
            write_vertices(geometry, world.meshes[mesh_id], nullptr);
            rtcUpdateGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0);
            rtcCommitGeometry(geometry);
            rtcCommitScene(mesh_scenes_[mesh_id].get());
        });
        device_.throw_if_error("rtcCommitScene(dynamic mesh)");
        for (InstanceId id : scene_.moving_instances()) {
            RTCGeometry geometry = instance_geometries_[id];
            rtcSetGeometryTransform(geometry, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR,
                                    &world.instances[id].object_to_world);
            rtcCommitGeometry(geometry);
        }
        // Instances of rebuilt mesh scenes must be committed again for the top to see them.
        for (InstanceId id : scene_.changing_instances())
            rtcCommitGeometry(instance_geometries_[id]);
        device_.throw_if_error("rtcCommitGeometry(instance)");
    } else {
        const std::vector<InstanceId>& changing = scene_.changing_instances();
        tbb::parallel_for(std::size_t(0), changing.size(), std::size_t(1), [&](std::size_t i) {
            const InstanceId id = changing[i];
            RTCGeometry geometry = geometries_[id];
            if (geometry == nullptr) return;
            const Instance& instance = world.instances[id];
            write_vertices(geometry, world.meshes[instance.mesh_id], &instance.object_to_world);
        });
        for (InstanceId id : changing) {
            if (geometries_[id] == nullptr) continue;
            rtcUpdateGeometryBuffer(geometries_[id], RTC_BUFFER_TYPE_VERTEX, 0);
            rtcCommitGeometry(geometries_[id]);
        }
        device_.throw_if_error("rtcCommitGeometry");
    }
    times.update_ms = update_timer.elapsed_ms();
    const BuildTimer top_timer;
    commit_scene(device_, top_scene_.get(), "rtcCommitScene");
    times.top_ms = top_timer.elapsed_ms();
    return times;
}

bool EmbreeDynamicAccel::is_traced_by_embree(const Ray& ray) {
    if (!(ray.tnear <= ray.tfar)) return false;
    if (ray.tnear < 0.0f || !is_finite(ray.org) || !is_finite(ray.dir))
        throw Error(
            "EmbreeDynamicAccel: ray with negative tnear or non-finite origin or "
            "direction");
    return true;
}

Hit EmbreeDynamicAccel::intersect_counted(const Ray& ray, TraversalCounters* /*counters*/) const {
    if (!is_traced_by_embree(ray)) return Hit{};
    return embree_closest_hit(top_scene_.get(), ray, mode_ == EmbreeDynamicMode::instanced);
}

bool EmbreeDynamicAccel::occluded(const Ray& ray) const {
    if (!is_traced_by_embree(ray)) return false;
    return embree_is_occluded(top_scene_.get(), ray);
}

AccelStats EmbreeDynamicAccel::stats() const {
    return stats_;
}

}  // namespace rebraid::glue
