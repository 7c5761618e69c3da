#include "embree_glue/dropin/embree_interposer_registry.h"

#include <atomic>
#include <memory>
#include <memory_resource>
#include <mutex>
#include <new>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "embree_glue/dropin/never_destroyed.h"

namespace rebraid::glue {
namespace {

/// Every record, keyed by Embree handle. Creation calls are rare next to ray queries, so one
/// mutex is enough; ray queries never touch the registry.
struct Registry {
    std::mutex mutex;
    /// Every record's memory: reused blocks instead of one malloc and free per record, which
    /// in glibc's heap, interleaved with Embree's own allocations, made releasing a scene of
    /// many geometries several times slower than Embree's own release.
    std::pmr::unsynchronized_pool_resource pool;
    std::pmr::unordered_map<RTCScene, RegisteredScene> scenes{&pool};
    std::pmr::unordered_map<RTCGeometry, RegisteredGeometry> geometries{&pool};
    std::pmr::unordered_map<RTCBuffer, RegisteredBuffer> buffers{&pool};
};

Registry& registry_instance() {
    static NeverDestroyed<Registry> registry;
    return registry.get();
}

std::atomic<bool> g_is_active{false};
std::atomic<bool> g_has_lost_records{false};

/// Runs `change` on the registry under its lock and marks the interposer active.
template <typename Change>
void with_registry(Change&& change) {
    g_is_active.store(true, std::memory_order_relaxed);
    Registry& registry = registry_instance();
    const std::lock_guard lock(registry.mutex);
    change(registry);
}

void erase_geometry_if_unused(Registry& registry, RTCGeometry geometry);

/// Embree frees a scene once neither the application nor an instance holds it; the record
/// goes with it (the handle may then be reused for a new scene) and lets go of its geometries.
void erase_scene_if_unused(Registry& registry, RTCScene scene) {
    const auto found = registry.scenes.find(scene);
    if (found == registry.scenes.end()) return;
    if (found->second.application_refs > 0 || found->second.instance_refs > 0) return;
    std::vector<RTCGeometry> held;
    for (const auto& [geom_id, geometry] : found->second.geometries) held.push_back(geometry);
    registry.scenes.erase(found);
    for (RTCGeometry geometry : held) {
        const auto record = registry.geometries.find(geometry);
        if (record == registry.geometries.end()) continue;
        if (record->second.scene_refs > 0) --record->second.scene_refs;
        erase_geometry_if_unused(registry, geometry);
    }
}

/// Same for geometries: alive while the application or a scene holds them.
void erase_geometry_if_unused(Registry& registry, RTCGeometry geometry) {
    const auto found = registry.geometries.find(geometry);
    if (found == registry.geometries.end()) return;
    if (found->second.application_refs > 0 || found->second.scene_refs > 0) return;
    const RTCScene instanced = found->second.instanced_scene;
    registry.geometries.erase(found);
    if (instanced == nullptr) return;
    const auto scene = registry.scenes.find(instanced);
    if (scene == registry.scenes.end()) return;
    if (scene->second.instance_refs > 0) --scene->second.instance_refs;
    erase_scene_if_unused(registry, instanced);
}

RegisteredGeometry* find_geometry(Registry& registry, RTCGeometry geometry) {
    const auto found = registry.geometries.find(geometry);
    return found == registry.geometries.end() ? nullptr : &found->second;
}

RegisteredScene* find_scene(Registry& registry, RTCScene scene) {
    const auto found = registry.scenes.find(scene);
    return found == registry.scenes.end() ? nullptr : &found->second;
}

/// A copy of the record of `handle` in `map` (one of the registry's maps), taken under the lock.
template <typename Record, typename Handle>
std::optional<Record> copy_record(std::pmr::unordered_map<Handle, Record> Registry::*map,
                                  Handle handle) {
    Registry& registry = registry_instance();
    const std::lock_guard lock(registry.mutex);
    const auto found = (registry.*map).find(handle);
    if (found == (registry.*map).end()) return std::nullopt;
    return found->second;
}

}  // namespace

// ---- RegisteredBuffers -----------------------------------------------------------------------

const RegisteredBufferView* RegisteredBuffers::find(BufferSlot slot) const {
    for (std::size_t i = 0; i < count_; ++i)
        if (entries_[i].first == slot) return &entries_[i].second;
    return nullptr;
}

const RegisteredBufferView& RegisteredBuffers::at(BufferSlot slot) const {
    const RegisteredBufferView* view = find(slot);
    if (view == nullptr) throw std::out_of_range("RegisteredBuffers::at: no buffer in that slot");
    return *view;
}

void RegisteredBuffers::set(BufferSlot slot, const RegisteredBufferView& view) {
    for (std::size_t i = 0; i < count_; ++i)
        if (entries_[i].first == slot) {
            entries_[i].second = view;
            return;
        }
    if (count_ == kCapacity) {
        has_overflowed_ = true;
        return;
    }
    entries_[count_++] = {slot, view};
}

// ---- Queries -------------------------------------------------------------------------------

std::optional<RegisteredSceneSnapshot> snapshot_registered_scene(RTCScene scene) {
    Registry& registry = registry_instance();
    const std::lock_guard lock(registry.mutex);
    if (registry.scenes.find(scene) == registry.scenes.end()) return std::nullopt;
    RegisteredSceneSnapshot snapshot;
    snapshot.root = scene;
    // Breadth first over scenes reached through instances (deeper levels are copied too so
    // that the converter can name a multi-level instance instead of missing it).
    std::vector<RTCScene> pending{scene};
    while (!pending.empty()) {
        const RTCScene current = pending.back();
        pending.pop_back();
        if (snapshot.scenes.contains(current)) continue;
        const RegisteredScene* record = find_scene(registry, current);
        if (record == nullptr) continue;  // an instance of an unknown scene: converter reports it
        snapshot.scenes.emplace(current, *record);
        for (const auto& [geom_id, geometry] : record->geometries) {
            const RegisteredGeometry* geometry_record = find_geometry(registry, geometry);
            if (geometry_record == nullptr) continue;
            snapshot.geometries.emplace(geometry, *geometry_record);
            if (geometry_record->instanced_scene != nullptr)
                pending.push_back(geometry_record->instanced_scene);
        }
    }
    return snapshot;
}

std::optional<RegisteredScene> find_registered_scene(RTCScene scene) {
    return copy_record(&Registry::scenes, scene);
}

std::optional<RegisteredGeometry> find_registered_geometry(RTCGeometry geometry) {
    return copy_record(&Registry::geometries, geometry);
}

std::optional<RegisteredBuffer> find_registered_buffer(RTCBuffer buffer) {
    return copy_record(&Registry::buffers, buffer);
}

RegistryCounts registry_counts() {
    Registry& registry = registry_instance();
    const std::lock_guard lock(registry.mutex);
    return {registry.scenes.size(), registry.geometries.size(), registry.buffers.size()};
}

bool is_interposer_active() {
    return g_is_active.load(std::memory_order_relaxed);
}

bool has_lost_records() {
    return g_has_lost_records.load(std::memory_order_relaxed);
}

// ---- Recording -----------------------------------------------------------------------------

namespace registry {

void on_new_scene(RTCScene scene) {
    if (scene == nullptr) return;
    // A reused handle starts a new record; its geometry map allocates from the pool too.
    with_registry([&](Registry& r) {
        // Constructed in place (an allocator does not travel by move assignment).
        RegisteredScene record{.geometries = std::pmr::map<unsigned int, RTCGeometry>(&r.pool)};
        r.scenes.insert_or_assign(scene, std::move(record));
    });
}

void on_retain_scene(RTCScene scene) {
    with_registry([&](Registry& r) {
        if (RegisteredScene* record = find_scene(r, scene)) ++record->application_refs;
    });
}

void on_release_scene(RTCScene scene) {
    with_registry([&](Registry& r) {
        RegisteredScene* record = find_scene(r, scene);
        if (record == nullptr || record->application_refs == 0) return;
        --record->application_refs;
        erase_scene_if_unused(r, scene);
    });
}

void on_commit_scene(RTCScene scene) {
    with_registry([&](Registry& r) {
        if (RegisteredScene* record = find_scene(r, scene)) {
            ++record->commit_count;
            record->has_uncommitted_changes = false;
        }
    });
}

void on_attach_geometry(RTCScene scene, RTCGeometry geometry, unsigned int geom_id) {
    if (geom_id == RTC_INVALID_GEOMETRY_ID) return;
    with_registry([&](Registry& r) {
        RegisteredScene* record = find_scene(r, scene);
        RegisteredGeometry* geometry_record = find_geometry(r, geometry);
        // Embree refuses an id that is taken; so does the registry.
        if (record == nullptr || geometry_record == nullptr || record->geometries.contains(geom_id))
            return;
        record->geometries.emplace(geom_id, geometry);
        record->has_uncommitted_changes = true;
        ++geometry_record->scene_refs;
    });
}

void on_detach_geometry(RTCScene scene, unsigned int geom_id) {
    with_registry([&](Registry& r) {
        RegisteredScene* record = find_scene(r, scene);
        if (record == nullptr) return;
        const auto found = record->geometries.find(geom_id);
        if (found == record->geometries.end()) return;
        const RTCGeometry geometry = found->second;
        record->geometries.erase(found);
        record->has_uncommitted_changes = true;
        if (RegisteredGeometry* geometry_record = find_geometry(r, geometry)) {
            if (geometry_record->scene_refs > 0) --geometry_record->scene_refs;
            erase_geometry_if_unused(r, geometry);
        }
    });
}

void on_new_geometry(RTCGeometry geometry, RTCGeometryType type) {
    if (geometry == nullptr) return;
    with_registry([&](Registry& r) {
        RegisteredGeometry record;
        record.type = type;
        r.geometries.insert_or_assign(geometry, std::move(record));
    });
}

void on_retain_geometry(RTCGeometry geometry) {
    with_registry([&](Registry& r) {
        if (RegisteredGeometry* record = find_geometry(r, geometry)) ++record->application_refs;
    });
}

void on_release_geometry(RTCGeometry geometry) {
    with_registry([&](Registry& r) {
        RegisteredGeometry* record = find_geometry(r, geometry);
        if (record == nullptr || record->application_refs == 0) return;
        --record->application_refs;
        erase_geometry_if_unused(r, geometry);
    });
}

void on_commit_geometry(RTCGeometry geometry) {
    with_registry([&](Registry& r) {
        if (RegisteredGeometry* record = find_geometry(r, geometry)) ++record->commit_count;
    });
}

void on_enable_geometry(RTCGeometry geometry, bool is_enabled) {
    with_registry([&](Registry& r) {
        if (RegisteredGeometry* record = find_geometry(r, geometry))
            record->is_enabled = is_enabled;
    });
}

void on_time_step_count(RTCGeometry geometry, unsigned int count) {
    with_registry([&](Registry& r) {
        if (RegisteredGeometry* record = find_geometry(r, geometry))
            record->time_step_count = count;
    });
}

void on_mask(RTCGeometry geometry, unsigned int mask) {
    with_registry([&](Registry& r) {
        if (RegisteredGeometry* record = find_geometry(r, geometry)) record->mask = mask;
    });
}

void on_filter_function(RTCGeometry geometry, bool is_set) {
    with_registry([&](Registry& r) {
        if (RegisteredGeometry* record = find_geometry(r, geometry))
            record->has_filter_function = record->has_filter_function || is_set;
    });
}

void on_set_buffer(RTCGeometry geometry, RTCBufferType type, unsigned int slot,
                   const RegisteredBufferView& view) {
    with_registry([&](Registry& r) {
        if (RegisteredGeometry* record = find_geometry(r, geometry))
            record->buffers.set(BufferSlot{type, slot}, view);
    });
}

void on_instanced_scene(RTCGeometry geometry, RTCScene scene) {
    with_registry([&](Registry& r) {
        RegisteredGeometry* record = find_geometry(r, geometry);
        if (record == nullptr) return;
        const RTCScene previous = record->instanced_scene;
        if (RegisteredScene* scene_record = find_scene(r, scene)) ++scene_record->instance_refs;
        record->instanced_scene = scene;
        if (RegisteredScene* old = find_scene(r, previous)) {
            if (old->instance_refs > 0) --old->instance_refs;
            erase_scene_if_unused(r, previous);
        }
    });
}

void on_transform(RTCGeometry geometry, unsigned int time_step,
                  const std::array<float, 12>& column_major) {
    if (time_step != 0) return;  // motion blur: the time step count already records it
    with_registry([&](Registry& r) {
        if (RegisteredGeometry* record = find_geometry(r, geometry))
            record->transform = column_major;
    });
}

void on_new_buffer(RTCBuffer buffer, const std::byte* data, std::size_t byte_size, bool is_shared) {
    if (buffer == nullptr) return;
    with_registry([&](Registry& r) {
        r.buffers.insert_or_assign(buffer, RegisteredBuffer{data, byte_size, is_shared, 1});
    });
}

void on_retain_buffer(RTCBuffer buffer) {
    with_registry([&](Registry& r) {
        const auto found = r.buffers.find(buffer);
        if (found != r.buffers.end()) ++found->second.application_refs;
    });
}

void on_release_buffer(RTCBuffer buffer) {
    // Geometries copy what they need of a buffer when it is bound, so the record can go as
    // soon as the application lets go (Embree keeps the memory while a geometry uses it).
    with_registry([&](Registry& r) {
        const auto found = r.buffers.find(buffer);
        if (found == r.buffers.end()) return;
        if (--found->second.application_refs == 0) r.buffers.erase(found);
    });
}

void on_lost_record() noexcept {
    g_has_lost_records.store(true, std::memory_order_relaxed);
}

}  // namespace registry
}  // namespace rebraid::glue
