#include "embree_glue/reference/embree_geometry.h"

#include <algorithm>
#include <cstddef>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>

#include "rebraid/core/error.h"

namespace rebraid::glue {

// Vertex and index data are copied as whole Vec3f/Triangle records and instance transforms
// are read straight from AffineTransform: these must be exactly the packed layouts Embree
// names RTC_FORMAT_FLOAT3, RTC_FORMAT_UINT3 and RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR.
static_assert(std::is_standard_layout_v<Vec3f> && sizeof(Vec3f) == 3 * sizeof(float));
static_assert(sizeof(Triangle) == 3 * sizeof(unsigned int));
static_assert(std::is_standard_layout_v<AffineTransform> &&
              sizeof(AffineTransform) == 12 * sizeof(float));
static_assert(offsetof(AffineTransform, col_x) == 0 * sizeof(float) &&
              offsetof(AffineTransform, col_y) == 3 * sizeof(float) &&
              offsetof(AffineTransform, col_z) == 6 * sizeof(float) &&
              offsetof(AffineTransform, translation) == 9 * sizeof(float));

RTCBuildQuality to_embree_quality(EmbreeBuildQuality quality) {
    switch (quality) {
        case EmbreeBuildQuality::low:
            return RTC_BUILD_QUALITY_LOW;
        case EmbreeBuildQuality::medium:
            return RTC_BUILD_QUALITY_MEDIUM;
        case EmbreeBuildQuality::high:
            return RTC_BUILD_QUALITY_HIGH;
    }
    throw Error("EmbreeBuildQuality: unknown value " + std::to_string(static_cast<int>(quality)));
}

void write_vertices(RTCGeometry geometry, const Mesh& mesh, const AffineTransform* to_world) {
    auto* vertices =
        static_cast<Vec3f*>(rtcGetGeometryBufferData(geometry, RTC_BUFFER_TYPE_VERTEX, 0));
    if (to_world != nullptr) {
        std::transform(mesh.positions.begin(), mesh.positions.end(), vertices,
                       [&](Vec3f p) { return to_world->transform_point(p); });
    } else {
        std::copy(mesh.positions.begin(), mesh.positions.end(), vertices);
    }
}

RTCGeometry attach_triangle_mesh(EmbreeDevice& device, RTCScene scene, const Mesh& mesh,
                                 const AffineTransform* to_world, unsigned int geom_id,
                                 RTCBuildQuality quality) {
    struct Releaser {
        void operator()(RTCGeometry geometry) const { rtcReleaseGeometry(geometry); }
    };
    // Ours until the scene holds it, released on every error path.
    std::unique_ptr<std::remove_pointer_t<RTCGeometry>, Releaser> geometry(
        rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_TRIANGLE));
    device.throw_if_error("rtcNewGeometry(triangles)");
    if (!geometry) throw Error("rtcNewGeometry: Embree returned no geometry");
    // Buffers Embree allocates itself are padded so that its 16-byte loads of the last vertex
    // stay in bounds; a shared buffer over Mesh::positions would not be.
    void* vertices =
        rtcSetNewGeometryBuffer(geometry.get(), RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                sizeof(Vec3f), mesh.positions.size());
    auto* indices = static_cast<Triangle*>(
        rtcSetNewGeometryBuffer(geometry.get(), RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                sizeof(Triangle), mesh.triangles.size()));
    device.throw_if_error("rtcSetNewGeometryBuffer");
    if (vertices == nullptr || indices == nullptr)
        throw Error("rtcSetNewGeometryBuffer: Embree returned no buffer");
    write_vertices(geometry.get(), mesh, to_world);
    std::copy(mesh.triangles.begin(), mesh.triangles.end(), indices);
    // Only matters at low scene quality, where Embree builds one BVH per geometry, and for
    // RTC_BUILD_QUALITY_REFIT.
    rtcSetGeometryBuildQuality(geometry.get(), quality);
    rtcCommitGeometry(geometry.get());
    device.throw_if_error("rtcCommitGeometry(triangles)");
    rtcAttachGeometryByID(scene, geometry.get(), geom_id);
    device.throw_if_error("rtcAttachGeometryByID(triangles)");
    // The scene holds its own reference now; ours goes.
    RTCGeometry attached = geometry.release();
    rtcReleaseGeometry(attached);
    return attached;
}

}  // namespace rebraid::glue
