#pragma once

// The drop-in's interposer (target rebraid::embree_dropin).
//
// embree_interposer.cpp defines, with C linkage and Embree's exact signatures, the Embree 3
// functions that create and change scenes, geometries and buffers (listed in docs/embree.md,
// "Using rebraid from an Embree application"). An executable that links the drop-in's static
// library before libembree3 gets these definitions for its own rtc* calls; each one looks the
// real function up once with dlsym(RTLD_NEXT, name), forwards the call with its arguments
// unchanged, returns the real result, and then records the call's effect in the registry
// (embree_interposer_registry.h). Embree's errors reach the application as before: the
// interposer never reads or clears the device error.
//
// Ray queries (rtcIntersect*, rtcOccluded*) are not interposed: tracing costs nothing extra.
// The preload library (embree_glue/preload/) defines them in addition, and learns of commits
// and releases through an InterposerObserver.

#include <embree3/rtcore.h>

extern "C" {
/// Defined in the interposer's object. The drop-in target passes
/// `-Wl,--undefined=rebraid_embree_interposer_anchor` to the linker, which pulls the
/// interposer out of the static library before any shared library is searched, so its
/// definitions win even when an application lists libembree3 first.
extern int rebraid_embree_interposer_anchor;
}

namespace rebraid::glue {

/// Told of the scene calls that change what a structure built from a scene may answer.
class InterposerObserver {
public:
    virtual ~InterposerObserver() = default;
    /// After rtcCommitScene or rtcJoinCommitScene (`is_join`: every thread that joined the
    /// commit returns from it, at different times) returned and the registry recorded it.
    virtual void scene_committed(RTCScene scene, bool is_join) noexcept = 0;
    /// Before rtcReleaseScene is forwarded (the scene and its record are still alive).
    virtual void scene_releasing(RTCScene scene) noexcept = 0;
};

/// Installs `observer` (null: none), which must outlive every later Embree call.
void set_interposer_observer(InterposerObserver* observer) noexcept;

}  // namespace rebraid::glue
