#include "embree_glue/preload/preload_scenes.h"

#include <cstdio>
#include <exception>
#include <optional>
#include <string>
#include <utility>

#include "embree_glue/dropin/embree_interposer_registry.h"
#include "rebraid/core/build_timer.h"
#include "rebraid/core/error.h"

namespace rebraid::glue {

constinit thread_local LastServedAnswer t_last_served_answer
    __attribute__((tls_model("initial-exec")));

namespace {

/// Throws rebraid::Error when a scene the structure would cover asks Embree for robust
/// intersection: EmbreeAccel traces such a scene with the watertight test, as Embree's robust
/// mode does, but reports t, u, v in the rounding of Embree's default kernels, not its robust
/// ones, so the hits would differ from Embree's in their last bits.
void check_scene_flags(RTCScene scene) {
    const std::optional<RegisteredSceneSnapshot> snapshot = snapshot_registered_scene(scene);
    if (!snapshot) return;  // EmbreeAccel says why it cannot serve the scene
    for (const auto& [each, record] : snapshot->scenes)
        if ((rtcGetSceneFlags(each) & RTC_SCENE_FLAG_ROBUST) != 0)
            throw Error(each == scene ? "the scene has RTC_SCENE_FLAG_ROBUST"
                                      : "an instanced scene has RTC_SCENE_FLAG_ROBUST");
}

std::size_t instanced_triangle_count(const Scene& scene) {
    std::size_t count = 0;
    for (const Instance& instance : scene.instances)
        count += scene.meshes[instance.mesh_id].triangles.size();
    return count;
}

std::string describe_structure(const EmbreeAccel& accel, double ms) {
    const Scene& scene = accel.converted_scene().scene;
    char text[160];
    std::snprintf(text, sizeof text, "%.1f ms, %zu instances, %zu triangles", ms,
                  scene.instances.size(), instanced_triangle_count(scene));
    return text;
}

}  // namespace

PreloadScenes::PreloadScenes(PreloadSettings settings) : settings_(std::move(settings)) {}

PreloadScenes::~PreloadScenes() {
    // The threads' last answers may name what this object built.
    generation_.fetch_add(1, std::memory_order_release);
}

ServedScene PreloadScenes::served_after_commit(RTCScene scene) noexcept {
    SceneState* state = nullptr;
    std::shared_ptr<tbb::collaborative_once_flag> decision;
    std::uint64_t generation = 0;
    {
        const std::lock_guard lock(mutex_);
        generation = generation_.load(std::memory_order_relaxed);
        const auto found = scenes_.find(scene);
        if (found != scenes_.end()) {
            state = &found->second;
            decision = state->decision;
        }
    }
    ServedScene served;
    if (state != nullptr) {
        // The record stays: only the scene's release or commit, during which the application
        // may not trace it, changes or erases it.
        tbb::collaborative_call_once(*decision, [&] { decide(scene, *state); });
        if (state->is_served) served = {state->accel.get()};
    }
    t_last_served_answer = {scene, generation, served};
    return served;
}

void PreloadScenes::decide(RTCScene scene, SceneState& state) noexcept {
    if (!settings_.is_enabled) return;
    const BuildTimer timer;
    std::unique_ptr<EmbreeAccel> built;
    std::unique_ptr<EmbreeAccel> discarded;
    std::string message;
    bool is_served = false;
    try {
        if (state.is_join_committed)
            throw Error("committed with rtcJoinCommitScene, which rebraid leaves to Embree");
        check_scene_flags(scene);
        if (state.accel) {
            state.accel->update();
            message = "rebraid serves it (updated: ";
        } else {
            built = std::make_unique<EmbreeAccel>(scene, settings_.accel);
            message = "rebraid serves it (build ";
        }
        is_served = true;
    } catch (const std::exception& error) {
        message = std::string("Embree serves it: ") + error.what();
    }
    {
        const std::lock_guard lock(mutex_);
        // Nothing is destroyed under the lock: a structure's destruction releases its scene,
        // which comes back through scene_releasing and takes the lock. (A structure built by
        // an earlier decision for the same scene can still be in place here.)
        if (built) {
            discarded = std::move(state.accel);
            state.accel = std::move(built);
        } else if (!is_served) {
            discarded = std::move(state.accel);
        }
        state.is_served = is_served;
    }
    if (is_served) message += describe_structure(*state.accel, timer.elapsed_ms()) + ")";
    log(scene, message);
    // `discarded` releases its reference to the scene here, outside the lock (the release
    // comes back through scene_releasing).
}

void PreloadScenes::scene_committed(RTCScene scene, bool is_join) noexcept {
    try {
        auto decision = std::make_shared<tbb::collaborative_once_flag>();
        const std::lock_guard lock(mutex_);
        SceneState& state = scenes_[scene];
        state.decision = std::move(decision);
        state.is_join_committed = is_join;
        generation_.fetch_add(1, std::memory_order_release);
    } catch (...) {
        // Out of memory: Embree answers the scene from now on.
        const std::lock_guard lock(mutex_);
        scenes_.erase(scene);
        generation_.fetch_add(1, std::memory_order_release);
    }
}

void PreloadScenes::scene_releasing(RTCScene scene) noexcept {
    std::unique_ptr<EmbreeAccel> released;
    {
        const std::lock_guard lock(mutex_);
        const auto found = scenes_.find(scene);
        if (found == scenes_.end()) return;
        const std::optional<RegisteredScene> record = find_registered_scene(scene);
        // The structure holds one reference of its own (EmbreeAccel retains its scene).
        const std::uint32_t own_refs = found->second.accel ? 1 : 0;
        const bool is_last_reference = !record || record->application_refs <= own_refs + 1;
        if (!is_last_reference) return;
        released = std::move(found->second.accel);
        scenes_.erase(found);
        generation_.fetch_add(1, std::memory_order_release);
    }
    // `released` lets go of its reference here, outside the lock; that release finds no record.
}

std::size_t PreloadScenes::scene_count() const {
    const std::lock_guard lock(mutex_);
    return scenes_.size();
}

void PreloadScenes::log(RTCScene scene, const std::string& message) const {
    if (!settings_.is_logging) return;
    std::fprintf(stderr, "rebraid preload: scene %p: %s\n", static_cast<const void*>(scene),
                 message.c_str());
}

}  // namespace rebraid::glue
