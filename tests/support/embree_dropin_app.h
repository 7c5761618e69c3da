#pragma once

// Shared by the drop-in's tests: an application's Embree code (a scene fed to Embree through
// every buffer path, as an application writes it) and the comparison of answers in Embree's
// conventions. Included only by executables that link rebraid::embree_dropin.

#include <rebraid/embree.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "rebraid/core/scene.h"
#include "rebraid/generators/random_rays.h"
#include "support/hit_comparison.h"

namespace rebraid::test {

inline constexpr float kInf = std::numeric_limits<float>::infinity();

// ---- An application's Embree code --------------------------------------------------------

/// The four ways an application can give Embree a triangle mesh's buffers.
enum class BufferPath { new_geometry_buffer, shared_geometry_buffer, new_buffer, shared_buffer };

/// Owns a device, as an application's renderer would.
struct Device {
    RTCDevice device = rtcNewDevice(nullptr);
    ~Device() { rtcReleaseDevice(device); }
    Device() = default;
    Device(const Device&) = delete;
    Device& operator=(const Device&) = delete;
};

/// Memory an application shares with Embree (must outlive the scenes). Vertices are stored
/// with a 16-byte stride, as applications with padded vertices do.
struct SharedMemory {
    std::vector<std::unique_ptr<std::vector<float>>> vertex_arrays;
    std::vector<std::unique_ptr<std::vector<std::uint32_t>>> index_arrays;
};

inline constexpr std::size_t kSharedVertexStride = 4 * sizeof(float);

/// A triangle geometry holding `mesh` (its vertices mapped by `to_world` when given), built
/// through `path`. Committed; the caller attaches and releases it.
inline RTCGeometry make_triangle_geometry(RTCDevice device, const Mesh& mesh, BufferPath path,
                                          SharedMemory& memory,
                                          const AffineTransform* to_world = nullptr) {
    const RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    const std::size_t vertex_count = mesh.positions.size();
    const std::size_t triangle_count = mesh.triangles.size();
    auto position = [&](std::size_t i) {
        return to_world != nullptr ? to_world->transform_point(mesh.positions[i])
                                   : mesh.positions[i];
    };
    switch (path) {
        case BufferPath::new_geometry_buffer: {
            auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
                geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, vertex_count));
            auto* indices = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(
                geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, triangle_count));
            for (std::size_t i = 0; i < vertex_count; ++i) {
                const Vec3f p = position(i);
                std::memcpy(vertices + 3 * i, &p, 12);
            }
            std::memcpy(indices, mesh.triangles.data(), triangle_count * 12);
            break;
        }
        case BufferPath::shared_geometry_buffer:
        case BufferPath::shared_buffer: {
            // One extra vertex in front: the buffers are bound with a byte offset.
            auto& vertices = *memory.vertex_arrays.emplace_back(
                std::make_unique<std::vector<float>>(4 * (vertex_count + 1), 0.0f));
            auto& indices = *memory.index_arrays.emplace_back(
                std::make_unique<std::vector<std::uint32_t>>(3 * triangle_count));
            for (std::size_t i = 0; i < vertex_count; ++i) {
                const Vec3f p = position(i);
                std::memcpy(&vertices[4 * (i + 1)], &p, 12);
            }
            std::memcpy(indices.data(), mesh.triangles.data(), triangle_count * 12);
            if (path == BufferPath::shared_geometry_buffer) {
                rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                           vertices.data(), kSharedVertexStride,
                                           kSharedVertexStride, vertex_count);
                rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                           indices.data(), 0, 12, triangle_count);
            } else {
                const RTCBuffer vertex_buffer =
                    rtcNewSharedBuffer(device, vertices.data(), vertices.size() * sizeof(float));
                const RTCBuffer index_buffer =
                    rtcNewSharedBuffer(device, indices.data(), indices.size() * 4);
                rtcSetGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                     vertex_buffer, kSharedVertexStride, kSharedVertexStride,
                                     vertex_count);
                rtcSetGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                     index_buffer, 0, 12, triangle_count);
                rtcReleaseBuffer(vertex_buffer);
                rtcReleaseBuffer(index_buffer);
            }
            break;
        }
        case BufferPath::new_buffer: {
            // Vertices and indices in one Embree buffer, indices first.
            const std::size_t index_bytes = triangle_count * 12;
            const std::size_t vertex_offset = (index_bytes + 15) / 16 * 16;
            const RTCBuffer buffer = rtcNewBuffer(device, vertex_offset + vertex_count * 12 + 4);
            auto* bytes = static_cast<std::byte*>(rtcGetBufferData(buffer));
            std::memcpy(bytes, mesh.triangles.data(), index_bytes);
            for (std::size_t i = 0; i < vertex_count; ++i) {
                const Vec3f p = position(i);
                std::memcpy(bytes + vertex_offset + 12 * i, &p, 12);
            }
            rtcSetGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, buffer, 0,
                                 12, triangle_count);
            rtcSetGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, buffer,
                                 vertex_offset, 12, vertex_count);
            rtcReleaseBuffer(buffer);
            break;
        }
    }
    rtcCommitGeometry(geometry);
    return geometry;
}

/// An application's instanced scene: one Embree scene per mesh (its triangles as geometry 0)
/// instanced from a top scene; every `flatten_every`-th instance is instead a world-space
/// triangle geometry of the top scene itself. Buffer paths rotate over the meshes. The
/// application releases what it no longer names (geometries after attaching, mesh scenes
/// after instancing), as Embree's tutorials do.
struct AppScene {
    RTCScene top = nullptr;
    SharedMemory memory;
    ~AppScene() {
        if (top != nullptr) rtcReleaseScene(top);
    }
};

inline BufferPath path_for(std::size_t index) {
    return BufferPath(index % 4);
}

inline std::unique_ptr<AppScene> feed_to_embree(RTCDevice device, const Scene& scene,
                                                std::size_t flatten_every = 0) {
    auto app = std::make_unique<AppScene>();
    std::vector<RTCScene> mesh_scenes;
    for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
        const RTCScene mesh_scene = rtcNewScene(device);
        const RTCGeometry geometry =
            make_triangle_geometry(device, scene.meshes[m], path_for(m), app->memory);
        rtcAttachGeometry(mesh_scene, geometry);
        rtcReleaseGeometry(geometry);
        rtcCommitScene(mesh_scene);
        mesh_scenes.push_back(mesh_scene);
    }
    app->top = rtcNewScene(device);
    for (std::size_t i = 0; i < scene.instances.size(); ++i) {
        const Instance& instance = scene.instances[i];
        RTCGeometry geometry = nullptr;
        if (flatten_every != 0 && i % flatten_every == 0) {
            geometry = make_triangle_geometry(device, scene.meshes[instance.mesh_id], path_for(i),
                                              app->memory, &instance.object_to_world);
        } else {
            geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(geometry, mesh_scenes[instance.mesh_id]);
            rtcSetGeometryTransform(geometry, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR,
                                    &instance.object_to_world);
            rtcCommitGeometry(geometry);
        }
        rtcAttachGeometry(app->top, geometry);
        rtcReleaseGeometry(geometry);
    }
    rtcCommitScene(app->top);
    for (RTCScene mesh_scene : mesh_scenes) rtcReleaseScene(mesh_scene);
    return app;
}

// ---- Comparing with Embree ---------------------------------------------------------------

inline RTCRayHit make_rayhit(const Ray& ray) {
    RTCRayHit rayhit{};
    rayhit.ray.org_x = ray.org.x;
    rayhit.ray.org_y = ray.org.y;
    rayhit.ray.org_z = ray.org.z;
    rayhit.ray.dir_x = ray.dir.x;
    rayhit.ray.dir_y = ray.dir.y;
    rayhit.ray.dir_z = ray.dir.z;
    rayhit.ray.tnear = ray.tnear;
    rayhit.ray.tfar = ray.tfar;
    rayhit.ray.mask = 0xffffffffu;
    rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rayhit.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    return rayhit;
}

inline bool is_hit(const RTCRayHit& rayhit) {
    return rayhit.hit.geomID != RTC_INVALID_GEOMETRY_ID;
}

inline bool grazes_edge(const RTCRayHit& rayhit, float edge_graze) {
    return is_hit(rayhit) &&
           std::min({rayhit.hit.u, rayhit.hit.v, 1.0f - rayhit.hit.u - rayhit.hit.v}) < edge_graze;
}

inline bool same_ids(const RTCRayHit& a, const RTCRayHit& b) {
    return a.hit.geomID == b.hit.geomID && a.hit.primID == b.hit.primID &&
           a.hit.instID[0] == b.hit.instID[0];
}

/// Embree's and the accel's answers on the same rays.
struct Answers {
    std::vector<RTCRayHit> hits;
    std::vector<float> occluded_tfar;
};

template <typename Intersect, typename Occluded>
inline Answers trace(const std::vector<Ray>& rays, Intersect&& intersect, Occluded&& occluded) {
    Answers answers;
    for (const Ray& ray : rays) {
        RTCRayHit rayhit = make_rayhit(ray);
        intersect(rayhit);
        answers.hits.push_back(rayhit);
        RTCRay occlusion_ray = make_rayhit(ray).ray;
        occluded(occlusion_ray);
        answers.occluded_tfar.push_back(occlusion_ray.tfar);
    }
    return answers;
}

inline Answers trace_embree(RTCScene scene, const std::vector<Ray>& rays) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    return trace(
        rays, [&](RTCRayHit& rayhit) { rtcIntersect1(scene, &context, &rayhit); },
        [&](RTCRay& ray) { rtcOccluded1(scene, &context, &ray); });
}

inline Answers trace_accel(const EmbreeAccel& accel, const std::vector<Ray>& rays) {
    return trace(
        rays, [&](RTCRayHit& rayhit) { accel.intersect1(rayhit); },
        [&](RTCRay& ray) { accel.occluded1(ray); });
}

/// The tolerance on barycentrics, and on Ng relative to its length.
inline constexpr float kAttributeTolerance = 1e-4f;

/// How closely the attributes of hits with the same ids agreed.
struct AttributeAgreement {
    std::size_t compared = 0;       ///< hits with the same ids on both sides
    std::size_t bit_identical = 0;  ///< of those, with t, u, v and Ng equal to the last bit
    float max_uv_difference = 0.0f;
    float max_relative_normal_difference = 0.0f;  ///< largest |Ng component difference| / |Ng|
};

/// Same hits as Embree: ids (unless two triangles are hit at the same t), t within the
/// project's tolerance, u and v within 1e-4, Ng within 1e-4 of its length, same occlusion;
/// rare disagreements only where a ray grazes an edge. Returns how closely the attributes
/// agreed.
inline AttributeAgreement expect_same_as_embree(const Answers& embree, const Answers& accel,
                                                const BBox3f& bounds) {
    AttributeAgreement agreement;
    EXPECT_EQ(embree.hits.size(), accel.hits.size());
    if (embree.hits.size() != accel.hits.size()) return agreement;
    const test::Tolerance tolerance = test::tolerance_for(bounds);
    std::size_t mismatches = 0, grazes = 0, ties = 0, hits = 0;
    for (std::size_t i = 0; i < embree.hits.size(); ++i) {
        const RTCRayHit& e = embree.hits[i];
        const RTCRayHit& a = accel.hits[i];
        hits += is_hit(e);
        const bool same_hit = is_hit(e) == is_hit(a) &&
                              (!is_hit(e) || test::same_t(e.ray.tfar, a.ray.tfar, tolerance));
        const bool same_occlusion =
            (embree.occluded_tfar[i] == -kInf) == (accel.occluded_tfar[i] == -kInf);
        if (!same_hit || !same_occlusion) {
            if (grazes_edge(e, tolerance.edge_graze) || grazes_edge(a, tolerance.edge_graze)) {
                ++grazes;
                continue;
            }
            if (++mismatches <= 5)
                ADD_FAILURE() << "ray " << i << ": Embree t=" << e.ray.tfar
                              << " geom=" << e.hit.geomID << " inst=" << e.hit.instID[0]
                              << " prim=" << e.hit.primID
                              << " occluded_tfar=" << embree.occluded_tfar[i]
                              << "; EmbreeAccel t=" << a.ray.tfar << " geom=" << a.hit.geomID
                              << " inst=" << a.hit.instID[0] << " prim=" << a.hit.primID
                              << " occluded_tfar=" << accel.occluded_tfar[i];
            continue;
        }
        if (!is_hit(e)) continue;
        if (!same_ids(e, a)) {  // a tie at the same t: either triangle may win; capped
            ++ties;
            continue;
        }
        ++agreement.compared;
        agreement.bit_identical += e.ray.tfar == a.ray.tfar && e.hit.u == a.hit.u &&
                                   e.hit.v == a.hit.v && e.hit.Ng_x == a.hit.Ng_x &&
                                   e.hit.Ng_y == a.hit.Ng_y && e.hit.Ng_z == a.hit.Ng_z;
        const float uv_difference =
            std::max(std::fabs(e.hit.u - a.hit.u), std::fabs(e.hit.v - a.hit.v));
        const float ng_length =
            std::sqrt(e.hit.Ng_x * e.hit.Ng_x + e.hit.Ng_y * e.hit.Ng_y + e.hit.Ng_z * e.hit.Ng_z);
        const float ng_difference =
            std::max({std::fabs(e.hit.Ng_x - a.hit.Ng_x), std::fabs(e.hit.Ng_y - a.hit.Ng_y),
                      std::fabs(e.hit.Ng_z - a.hit.Ng_z)}) /
            ng_length;
        agreement.max_uv_difference = std::max(agreement.max_uv_difference, uv_difference);
        agreement.max_relative_normal_difference =
            std::max(agreement.max_relative_normal_difference, ng_difference);
        const bool same_attributes =
            uv_difference <= kAttributeTolerance && ng_difference <= kAttributeTolerance;
        if (!same_attributes && ++mismatches <= 5)
            ADD_FAILURE() << "ray " << i << " (geom " << e.hit.geomID << " prim " << e.hit.primID
                          << "): Embree u,v=" << e.hit.u << "," << e.hit.v << " Ng=" << e.hit.Ng_x
                          << "," << e.hit.Ng_y << "," << e.hit.Ng_z
                          << "; EmbreeAccel u,v=" << a.hit.u << "," << a.hit.v
                          << " Ng=" << a.hit.Ng_x << "," << a.hit.Ng_y << "," << a.hit.Ng_z;
    }
    EXPECT_EQ(mismatches, 0u);
    EXPECT_LE(double(grazes), tolerance.max_fragile_fraction * double(embree.hits.size()))
        << grazes << " rays disagree at grazed edges";
    EXPECT_LE(double(ties), tolerance.max_tie_fraction * double(embree.hits.size()))
        << ties << " rays hit another triangle at the same t";
    EXPECT_GT(hits, embree.hits.size() / 50) << "too few rays hit the scene";
    EXPECT_GT(agreement.compared, hits * 9 / 10) << "too few hits with identical ids";
    // The README's promise: where both find the same triangle, t, u, v and Ng are Embree's to
    // the last bit (the default device's kernels, reproduced by embree_hit_attributes.cpp).
    EXPECT_EQ(agreement.bit_identical, agreement.compared) << "hits not bit-identical to Embree's";
    std::printf(
        "[ attributes ] %zu hits compared, %zu bit-identical, max |du|,|dv| %.3g, "
        "max |dNg|/|Ng| %.3g\n",
        agreement.compared, agreement.bit_identical, double(agreement.max_uv_difference),
        double(agreement.max_relative_normal_difference));
    return agreement;
}

inline constexpr std::size_t kRayCount = 10000;

inline AttributeAgreement expect_accel_matches_embree(RTCScene scene, const EmbreeAccel& accel,
                                                      std::uint64_t seed) {
    const std::vector<Ray> rays = generate_random_rays(accel.bounds(), kRayCount, seed);
    return expect_same_as_embree(trace_embree(scene, rays), trace_accel(accel, rays),
                                 accel.bounds());
}

/// A single-triangle mesh for registry tests.
inline Mesh one_triangle() {
    Mesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 2}};
    return mesh;
}

}  // namespace rebraid::test
