#include "embree_glue/dropin/embree_interposer.h"

#include <embree3/rtcore.h>

#include <array>
#include <atomic>
#include <cstddef>
#include <optional>

#include "embree_glue/dropin/embree_interposer_registry.h"
#include "embree_glue/dropin/embree_next_definition.h"

extern "C" {
int rebraid_embree_interposer_anchor = 0;
}

namespace {

using namespace rebraid::glue;

/// Runs a registry update; an exception (out of memory) must not cross into the
/// application's C frames, so it is recorded instead (EmbreeAccel then refuses to build).
template <typename Record>
void record(Record&& update) noexcept {
    try {
        update();
    } catch (...) {
        registry::on_lost_record();
    }
}

/// The effect of rtcSetGeometryTransform in FLOAT3X4_COLUMN_MAJOR, or false for a format
/// Embree rejects.
bool to_column_major(RTCFormat format, const float* xfm, std::array<float, 12>& out) {
    if (xfm == nullptr) return false;
    for (int column = 0; column < 4; ++column)
        for (int row = 0; row < 3; ++row) {
            float value = 0.0f;
            switch (format) {
                case RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR:
                    value = xfm[column * 3 + row];
                    break;
                case RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR:
                    value = xfm[column * 4 + row];
                    break;
                case RTC_FORMAT_FLOAT3X4_ROW_MAJOR:
                    value = xfm[row * 4 + column];
                    break;
                default:
                    return false;
            }
            out[std::size_t(column * 3 + row)] = value;
        }
    return true;
}

std::atomic<InterposerObserver*> g_observer{nullptr};

RegisteredBufferView make_view(BufferSource source, RTCFormat format, const void* base,
                               std::size_t byte_offset, std::size_t byte_stride,
                               std::size_t item_count, RTCBuffer buffer) {
    RegisteredBufferView view;
    view.source = source;
    view.format = format;
    view.data = base == nullptr ? nullptr : static_cast<const std::byte*>(base) + byte_offset;
    view.byte_offset = byte_offset;
    view.byte_stride = byte_stride;
    view.item_count = item_count;
    view.buffer = buffer;
    return view;
}

}  // namespace

void rebraid::glue::set_interposer_observer(InterposerObserver* observer) noexcept {
    g_observer.store(observer, std::memory_order_release);
}

// Each definition: forward, then record. Releases record first, while the handle is still
// alive, so a handle Embree reuses at once cannot be confused with the released one.

extern "C" {

// ---- Scenes --------------------------------------------------------------------------------

RTCScene rtcNewScene(RTCDevice device) {
    static auto* const real = next_definition<decltype(rtcNewScene)>("rtcNewScene");
    const RTCScene scene = call_real(real, device);
    record([&] { registry::on_new_scene(scene); });
    return scene;
}

void rtcRetainScene(RTCScene scene) {
    static auto* const real = next_definition<decltype(rtcRetainScene)>("rtcRetainScene");
    call_real(real, scene);
    record([&] { registry::on_retain_scene(scene); });
}

void rtcReleaseScene(RTCScene scene) {
    static auto* const real = next_definition<decltype(rtcReleaseScene)>("rtcReleaseScene");
    if (InterposerObserver* observer = g_observer.load(std::memory_order_acquire))
        observer->scene_releasing(scene);
    call_real(real, scene);
    record([&] { registry::on_release_scene(scene); });
}

void rtcCommitScene(RTCScene scene) {
    static auto* const real = next_definition<decltype(rtcCommitScene)>("rtcCommitScene");
    call_real(real, scene);
    record([&] { registry::on_commit_scene(scene); });
    if (InterposerObserver* observer = g_observer.load(std::memory_order_acquire))
        observer->scene_committed(scene, false);
}

void rtcJoinCommitScene(RTCScene scene) {
    static auto* const real = next_definition<decltype(rtcJoinCommitScene)>("rtcJoinCommitScene");
    call_real(real, scene);
    record([&] { registry::on_commit_scene(scene); });
    if (InterposerObserver* observer = g_observer.load(std::memory_order_acquire))
        observer->scene_committed(scene, true);
}

unsigned int rtcAttachGeometry(RTCScene scene, RTCGeometry geometry) {
    static auto* const real = next_definition<decltype(rtcAttachGeometry)>("rtcAttachGeometry");
    const unsigned int geom_id =
        real == nullptr ? RTC_INVALID_GEOMETRY_ID : call_real(real, scene, geometry);
    record([&] { registry::on_attach_geometry(scene, geometry, geom_id); });
    return geom_id;
}

void rtcAttachGeometryByID(RTCScene scene, RTCGeometry geometry, unsigned int geomID) {
    static auto* const real =
        next_definition<decltype(rtcAttachGeometryByID)>("rtcAttachGeometryByID");
    call_real(real, scene, geometry, geomID);
    record([&] { registry::on_attach_geometry(scene, geometry, geomID); });
}

void rtcDetachGeometry(RTCScene scene, unsigned int geomID) {
    static auto* const real = next_definition<decltype(rtcDetachGeometry)>("rtcDetachGeometry");
    record([&] { registry::on_detach_geometry(scene, geomID); });
    call_real(real, scene, geomID);
}

// ---- Geometries ----------------------------------------------------------------------------

RTCGeometry rtcNewGeometry(RTCDevice device, enum RTCGeometryType type) {
    static auto* const real = next_definition<decltype(rtcNewGeometry)>("rtcNewGeometry");
    const RTCGeometry geometry = call_real(real, device, type);
    record([&] { registry::on_new_geometry(geometry, type); });
    return geometry;
}

void rtcRetainGeometry(RTCGeometry geometry) {
    static auto* const real = next_definition<decltype(rtcRetainGeometry)>("rtcRetainGeometry");
    call_real(real, geometry);
    record([&] { registry::on_retain_geometry(geometry); });
}

void rtcReleaseGeometry(RTCGeometry geometry) {
    static auto* const real = next_definition<decltype(rtcReleaseGeometry)>("rtcReleaseGeometry");
    record([&] { registry::on_release_geometry(geometry); });
    call_real(real, geometry);
}

void rtcCommitGeometry(RTCGeometry geometry) {
    static auto* const real = next_definition<decltype(rtcCommitGeometry)>("rtcCommitGeometry");
    call_real(real, geometry);
    record([&] { registry::on_commit_geometry(geometry); });
}

void rtcEnableGeometry(RTCGeometry geometry) {
    static auto* const real = next_definition<decltype(rtcEnableGeometry)>("rtcEnableGeometry");
    call_real(real, geometry);
    record([&] { registry::on_enable_geometry(geometry, true); });
}

void rtcDisableGeometry(RTCGeometry geometry) {
    static auto* const real = next_definition<decltype(rtcDisableGeometry)>("rtcDisableGeometry");
    call_real(real, geometry);
    record([&] { registry::on_enable_geometry(geometry, false); });
}

void rtcSetGeometryTimeStepCount(RTCGeometry geometry, unsigned int timeStepCount) {
    static auto* const real =
        next_definition<decltype(rtcSetGeometryTimeStepCount)>("rtcSetGeometryTimeStepCount");
    call_real(real, geometry, timeStepCount);
    record([&] { registry::on_time_step_count(geometry, timeStepCount); });
}

void rtcSetGeometryMask(RTCGeometry geometry, unsigned int mask) {
    static auto* const real = next_definition<decltype(rtcSetGeometryMask)>("rtcSetGeometryMask");
    call_real(real, geometry, mask);
    record([&] { registry::on_mask(geometry, mask); });
}

void rtcSetGeometryIntersectFilterFunction(RTCGeometry geometry, RTCFilterFunctionN filter) {
    static auto* const real = next_definition<decltype(rtcSetGeometryIntersectFilterFunction)>(
        "rtcSetGeometryIntersectFilterFunction");
    call_real(real, geometry, filter);
    record([&] { registry::on_filter_function(geometry, filter != nullptr); });
}

void rtcSetGeometryOccludedFilterFunction(RTCGeometry geometry, RTCFilterFunctionN filter) {
    static auto* const real = next_definition<decltype(rtcSetGeometryOccludedFilterFunction)>(
        "rtcSetGeometryOccludedFilterFunction");
    call_real(real, geometry, filter);
    record([&] { registry::on_filter_function(geometry, filter != nullptr); });
}

// ---- Geometry buffers ----------------------------------------------------------------------

void rtcSetGeometryBuffer(RTCGeometry geometry, enum RTCBufferType type, unsigned int slot,
                          enum RTCFormat format, RTCBuffer buffer, size_t byteOffset,
                          size_t byteStride, size_t itemCount) {
    static auto* const real =
        next_definition<decltype(rtcSetGeometryBuffer)>("rtcSetGeometryBuffer");
    call_real(real, geometry, type, slot, format, buffer, byteOffset, byteStride, itemCount);
    record([&] {
        const std::optional<RegisteredBuffer> known = find_registered_buffer(buffer);
        if (!known) return;  // not made through the interposer: nothing to read it with
        registry::on_set_buffer(geometry, type, slot,
                                make_view(BufferSource::embree_buffer, format, known->data,
                                          byteOffset, byteStride, itemCount, buffer));
    });
}

void rtcSetSharedGeometryBuffer(RTCGeometry geometry, enum RTCBufferType type, unsigned int slot,
                                enum RTCFormat format, const void* ptr, size_t byteOffset,
                                size_t byteStride, size_t itemCount) {
    static auto* const real =
        next_definition<decltype(rtcSetSharedGeometryBuffer)>("rtcSetSharedGeometryBuffer");
    call_real(real, geometry, type, slot, format, ptr, byteOffset, byteStride, itemCount);
    record([&] {
        registry::on_set_buffer(geometry, type, slot,
                                make_view(BufferSource::shared_geometry_buffer, format, ptr,
                                          byteOffset, byteStride, itemCount, nullptr));
    });
}

void* rtcSetNewGeometryBuffer(RTCGeometry geometry, enum RTCBufferType type, unsigned int slot,
                              enum RTCFormat format, size_t byteStride, size_t itemCount) {
    static auto* const real =
        next_definition<decltype(rtcSetNewGeometryBuffer)>("rtcSetNewGeometryBuffer");
    void* data = call_real(real, geometry, type, slot, format, byteStride, itemCount);
    if (data != nullptr)
        record([&] {
            registry::on_set_buffer(geometry, type, slot,
                                    make_view(BufferSource::new_geometry_buffer, format, data, 0,
                                              byteStride, itemCount, nullptr));
        });
    return data;
}

// ---- Instances -----------------------------------------------------------------------------

void rtcSetGeometryInstancedScene(RTCGeometry geometry, RTCScene scene) {
    static auto* const real =
        next_definition<decltype(rtcSetGeometryInstancedScene)>("rtcSetGeometryInstancedScene");
    call_real(real, geometry, scene);
    record([&] { registry::on_instanced_scene(geometry, scene); });
}

void rtcSetGeometryTransform(RTCGeometry geometry, unsigned int timeStep, enum RTCFormat format,
                             const void* xfm) {
    static auto* const real =
        next_definition<decltype(rtcSetGeometryTransform)>("rtcSetGeometryTransform");
    call_real(real, geometry, timeStep, format, xfm);
    record([&] {
        std::array<float, 12> column_major{};
        if (to_column_major(format, static_cast<const float*>(xfm), column_major))
            registry::on_transform(geometry, timeStep, column_major);
    });
}

void rtcSetGeometryTransformQuaternion(RTCGeometry geometry, unsigned int timeStep,
                                       const struct RTCQuaternionDecomposition* qd) {
    static auto* const real = next_definition<decltype(rtcSetGeometryTransformQuaternion)>(
        "rtcSetGeometryTransformQuaternion");
    call_real(real, geometry, timeStep, qd);
    // Embree's own reading of the decomposition, as a matrix (time 0 is time step 0).
    if (timeStep != 0 || qd == nullptr || real == nullptr) return;
    std::array<float, 12> column_major{};
    rtcGetGeometryTransform(geometry, 0.0f, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, column_major.data());
    record([&] { registry::on_transform(geometry, 0, column_major); });
}

// ---- Buffers -------------------------------------------------------------------------------

RTCBuffer rtcNewBuffer(RTCDevice device, size_t byteSize) {
    static auto* const real = next_definition<decltype(rtcNewBuffer)>("rtcNewBuffer");
    const RTCBuffer buffer = call_real(real, device, byteSize);
    if (buffer != nullptr) {
        const void* data = rtcGetBufferData(buffer);  // not interposed: Embree's own
        record([&] {
            registry::on_new_buffer(buffer, static_cast<const std::byte*>(data), byteSize, false);
        });
    }
    return buffer;
}

RTCBuffer rtcNewSharedBuffer(RTCDevice device, void* ptr, size_t byteSize) {
    static auto* const real = next_definition<decltype(rtcNewSharedBuffer)>("rtcNewSharedBuffer");
    const RTCBuffer buffer = call_real(real, device, ptr, byteSize);
    record([&] {
        registry::on_new_buffer(buffer, static_cast<const std::byte*>(ptr), byteSize, true);
    });
    return buffer;
}

void rtcRetainBuffer(RTCBuffer buffer) {
    static auto* const real = next_definition<decltype(rtcRetainBuffer)>("rtcRetainBuffer");
    call_real(real, buffer);
    record([&] { registry::on_retain_buffer(buffer); });
}

void rtcReleaseBuffer(RTCBuffer buffer) {
    static auto* const real = next_definition<decltype(rtcReleaseBuffer)>("rtcReleaseBuffer");
    record([&] { registry::on_release_buffer(buffer); });
    call_real(real, buffer);
}

}  // extern "C"
