#pragma once

// What the drop-in learned about the application's Embree objects. Embree 3's public API
// cannot list a scene's geometries, read back a buffer's item count or an instance's scene,
// so embree_interposer.cpp defines Embree's scene-creation functions, forwards each call to
// the real Embree and records its effect here. EmbreeAccel reads the records through the
// snapshot functions at the end of this header.

#include <embree3/rtcore.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory_resource>
#include <optional>
#include <utility>

namespace rebraid::glue {

/// How the application gave Embree a geometry buffer.
enum class BufferSource {
    new_geometry_buffer,     ///< rtcSetNewGeometryBuffer: Embree allocated it
    shared_geometry_buffer,  ///< rtcSetSharedGeometryBuffer: the application's memory
    embree_buffer,           ///< rtcSetGeometryBuffer with an RTCBuffer
};

/// One buffer bound to a geometry slot, as the application described it.
struct RegisteredBufferView {
    BufferSource source = BufferSource::new_geometry_buffer;
    RTCFormat format = RTC_FORMAT_UNDEFINED;
    /// First byte of item 0 (the byte offset already applied). Embree keeps the memory alive
    /// while the geometry holds the buffer; the application owns shared memory.
    const std::byte* data = nullptr;
    std::size_t byte_offset = 0;  ///< offset into the buffer or shared memory
    std::size_t byte_stride = 0;
    std::size_t item_count = 0;
    RTCBuffer buffer = nullptr;  ///< the RTCBuffer for BufferSource::embree_buffer, else null
};

/// A (buffer type, slot) pair, the key of a geometry's buffers.
using BufferSlot = std::pair<RTCBufferType, unsigned int>;

/// The buffers bound to one geometry, by slot. Held inline (no allocation per geometry: the
/// interposer must not slow down scene creation); slots past the capacity are not recorded
/// (has_overflowed), which only matters for vertex-attribute or motion-blur slots.
class RegisteredBuffers {
public:
    static constexpr std::size_t kCapacity = 8;

    /// The view bound to `slot`, or null.
    const RegisteredBufferView* find(BufferSlot slot) const;
    /// The view bound to `slot`; throws std::out_of_range when there is none.
    const RegisteredBufferView& at(BufferSlot slot) const;
    /// Binds `view` to `slot`, replacing what was bound there.
    void set(BufferSlot slot, const RegisteredBufferView& view);
    std::size_t size() const { return count_; }
    bool has_overflowed() const { return has_overflowed_; }

private:
    std::array<std::pair<BufferSlot, RegisteredBufferView>, kCapacity> entries_{};
    std::size_t count_ = 0;
    bool has_overflowed_ = false;
};

/// An RTCBuffer made by rtcNewBuffer or rtcNewSharedBuffer.
struct RegisteredBuffer {
    const std::byte* data = nullptr;  ///< rtcGetBufferData
    std::size_t byte_size = 0;
    bool is_shared = false;              ///< rtcNewSharedBuffer
    std::uint32_t application_refs = 1;  ///< 1 + retains - releases
};

/// An RTCGeometry and the state the drop-in needs of it.
struct RegisteredGeometry {
    RTCGeometryType type = RTC_GEOMETRY_TYPE_TRIANGLE;
    RegisteredBuffers buffers;
    /// rtcSetGeometryInstancedScene (instances only).
    RTCScene instanced_scene = nullptr;
    /// Time step 0 of the instance transform, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR (identity until
    /// set), whatever format or quaternion form the application used.
    std::array<float, 12> transform = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    std::uint32_t time_step_count = 1;  ///< more than 1 = motion blur
    std::uint32_t mask = 0xffffffffu;   ///< Embree's default: every ray sees it
    bool is_enabled = true;
    bool has_filter_function = false;  ///< intersect or occluded filter set
    /// rtcCommitGeometry calls so far (tells update() what the application touched).
    std::uint64_t commit_count = 0;
    std::uint32_t application_refs = 1;  ///< 1 + retains - releases
    std::uint32_t scene_refs = 0;        ///< scenes it is attached to
};

/// An RTCScene: its attached geometries by geomID.
struct RegisteredScene {
    /// geomID -> geometry, ascending ids. The registry's own records allocate from its pool.
    std::pmr::map<unsigned int, RTCGeometry> geometries;
    std::uint64_t commit_count = 0;  ///< rtcCommitScene calls so far
    /// An attach or detach happened after the last rtcCommitScene.
    bool has_uncommitted_changes = false;
    std::uint32_t application_refs = 1;  ///< 1 + retains - releases
    std::uint32_t instance_refs = 0;     ///< instance geometries instancing it
};

/// A consistent copy of a scene and of everything it reaches (its geometries, the scenes its
/// instances instance and their geometries), taken under the registry's lock.
struct RegisteredSceneSnapshot {
    RTCScene root = nullptr;
    std::map<RTCScene, RegisteredScene> scenes;            ///< root and instanced scenes
    std::map<RTCGeometry, RegisteredGeometry> geometries;  ///< every geometry they hold
};

/// The snapshot of `scene`, or nothing when the registry never saw it created (the
/// application was not linked against the drop-in before Embree, or the scene was released).
std::optional<RegisteredSceneSnapshot> snapshot_registered_scene(RTCScene scene);

/// Single records, for tests and diagnostics; nothing when unknown or released.
std::optional<RegisteredScene> find_registered_scene(RTCScene scene);
std::optional<RegisteredGeometry> find_registered_geometry(RTCGeometry geometry);
std::optional<RegisteredBuffer> find_registered_buffer(RTCBuffer buffer);

/// Live records (for tests: released objects drop out).
struct RegistryCounts {
    std::size_t scenes = 0;
    std::size_t geometries = 0;
    std::size_t buffers = 0;
};
RegistryCounts registry_counts();

/// True once any interposed Embree call has run in this process: the application's calls
/// reach the drop-in (it was linked before Embree).
bool is_interposer_active();

/// True when recording some call failed (out of memory): the registry may then miss objects,
/// and EmbreeAccel refuses to trust it.
bool has_lost_records();

// ---- Recording, called by embree_interposer.cpp after the real Embree call returned --------
// Each takes the call's arguments and result; a null handle (Embree refused) records nothing.
namespace registry {
void on_new_scene(RTCScene scene);
void on_retain_scene(RTCScene scene);
void on_release_scene(RTCScene scene);
void on_commit_scene(RTCScene scene);
void on_attach_geometry(RTCScene scene, RTCGeometry geometry, unsigned int geom_id);
void on_detach_geometry(RTCScene scene, unsigned int geom_id);

void on_new_geometry(RTCGeometry geometry, RTCGeometryType type);
void on_retain_geometry(RTCGeometry geometry);
void on_release_geometry(RTCGeometry geometry);
void on_commit_geometry(RTCGeometry geometry);
void on_enable_geometry(RTCGeometry geometry, bool is_enabled);
void on_time_step_count(RTCGeometry geometry, unsigned int count);
void on_mask(RTCGeometry geometry, unsigned int mask);
void on_filter_function(RTCGeometry geometry, bool is_set);
void on_set_buffer(RTCGeometry geometry, RTCBufferType type, unsigned int slot,
                   const RegisteredBufferView& view);
void on_instanced_scene(RTCGeometry geometry, RTCScene scene);
/// `column_major` is the transform of time step `time_step` in FLOAT3X4_COLUMN_MAJOR.
void on_transform(RTCGeometry geometry, unsigned int time_step,
                  const std::array<float, 12>& column_major);

void on_new_buffer(RTCBuffer buffer, const std::byte* data, std::size_t byte_size, bool is_shared);
void on_retain_buffer(RTCBuffer buffer);
void on_release_buffer(RTCBuffer buffer);
/// Records that recording a call failed (see has_lost_records()).
void on_lost_record() noexcept;
}  // namespace registry

}  // namespace rebraid::glue
