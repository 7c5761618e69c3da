#pragma once

#include <embree3/rtcore.h>

#include "embree_glue/reference/embree_device.h"

namespace rebraid::glue {

/// Owns one reference to an RTCScene (move-only); releases it on destruction. The scene keeps
/// its device alive by itself (Embree reference-counts devices), but errors are only reported
/// while the EmbreeDevice wrapper exists, so keep the wrapper at least as long.
class EmbreeSceneHandle {
public:
    /// Creates an empty scene on `device`. Throws rebraid::Error when Embree refuses.
    explicit EmbreeSceneHandle(EmbreeDevice& device);
    ~EmbreeSceneHandle();

    EmbreeSceneHandle(EmbreeSceneHandle&& other) noexcept;
    EmbreeSceneHandle& operator=(EmbreeSceneHandle&& other) noexcept;
    EmbreeSceneHandle(const EmbreeSceneHandle&) = delete;
    EmbreeSceneHandle& operator=(const EmbreeSceneHandle&) = delete;

    /// The raw handle for rtc* calls; null only in a moved-from handle.
    RTCScene get() const { return scene_; }

private:
    RTCScene scene_ = nullptr;
};

}  // namespace rebraid::glue
