#pragma once

#include <embree3/rtcore.h>
#include <tbb/collaborative_call_once.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

#include "embree_glue/dropin/embree_accel.h"
#include "embree_glue/dropin/embree_interposer.h"
#include "embree_glue/preload/preload_settings.h"

namespace rebraid::glue {

/// The preload library's scenes: for each committed scene, whether rebraid or Embree answers
/// its rays, and the structure that does.
///
/// The decision is made when the scene is first traced after each commit, so that scenes only
/// reached through instances (never traced themselves) cost nothing at commit. It converts the
/// scene (EmbreeAccel: anything it cannot reproduce exactly leaves the scene to Embree), then
/// builds the structure, or updates the one built for the previous commit. Threads tracing the
/// scene meanwhile wait for it and help with the build (tbb::collaborative_call_once).
///
/// Embree's rules make the lookups safe without a lock per ray: a scene is neither traced while
/// it is committed nor after its release. A thread remembers its last answer together with a
/// generation that every commit and release moves on, and asks again when it changed.
/// What answers a scene's rays.
struct ServedScene {
    const EmbreeAccel* accel = nullptr;  ///< null: Embree
};

/// A thread's last answer of PreloadScenes::served, valid while the generation it was given
/// at is current. The library is loaded at start (LD_PRELOAD), so its thread-local storage is
/// static and read without a call; constinit: no initialisation to call for either.
struct LastServedAnswer {
    RTCScene scene = nullptr;
    std::uint64_t generation = 0;
    ServedScene served;
};
extern constinit thread_local LastServedAnswer t_last_served_answer
    __attribute__((tls_model("initial-exec")));

class PreloadScenes final : public InterposerObserver {
public:
    explicit PreloadScenes(PreloadSettings settings);
    ~PreloadScenes() override;

    PreloadScenes(const PreloadScenes&) = delete;
    PreloadScenes& operator=(const PreloadScenes&) = delete;

    /// The structure answering the rays of `scene`; Embree's (null) when the scene was never
    /// committed or cannot be served.
    ServedScene served(RTCScene scene) noexcept {
        if (const ServedScene* last = last_answer(scene)) return *last;
        return served_after_commit(scene);
    }
    /// This thread's last answer for `scene` while it stands (no commit or release since),
    /// else null. Inline: every traced ray asks, and nearly always it stands. Static: the
    /// generation is the process's, so that asking needs no PreloadScenes.
    static const ServedScene* last_answer(RTCScene scene) noexcept {
        const LastServedAnswer& last = t_last_served_answer;
        if (last.scene == scene && last.generation == generation_.load(std::memory_order_acquire))
            return &last.served;
        return nullptr;
    }
    /// Starts a new decision for the scene's next trace. A scene committed with
    /// rtcJoinCommitScene is left to Embree: a thread may trace it as soon as its own join
    /// returns, while the other joiners' calls still come in.
    void scene_committed(RTCScene scene, bool is_join) noexcept override;
    /// Frees what was built for the scene when this is the application's last reference.
    void scene_releasing(RTCScene scene) noexcept override;

    /// Scenes with a record (for tests: released scenes drop out).
    std::size_t scene_count() const;

private:
    struct SceneState {
        /// Made anew at each commit: the decision for that commit runs once. Shared with the
        /// threads waiting for it.
        std::shared_ptr<tbb::collaborative_once_flag> decision;
        /// Built for an earlier commit or this one; kept to be updated by the next commit.
        std::unique_ptr<EmbreeAccel> accel;
        bool is_served = false;          ///< the decision for the last commit was rebraid
        bool is_join_committed = false;  ///< committed with rtcJoinCommitScene
    };

    ServedScene served_after_commit(RTCScene scene) noexcept;
    void decide(RTCScene scene, SceneState& state) noexcept;
    void log(RTCScene scene, const std::string& message) const;

    const PreloadSettings settings_;
    mutable std::mutex mutex_;
    std::unordered_map<RTCScene, SceneState> scenes_;
    /// Counts the commits, releases and PreloadScenes destroyed in the process: an answer
    /// given at an earlier generation does not stand. One for the process, as the threads'
    /// last answers are.
    static inline constinit std::atomic<std::uint64_t> generation_{1};
};

}  // namespace rebraid::glue
