#include "embree_glue/reference/embree_scene_handle.h"

#include <utility>

#include "rebraid/core/error.h"

namespace rebraid::glue {

EmbreeSceneHandle::EmbreeSceneHandle(EmbreeDevice& device) {
    scene_ = rtcNewScene(device.get());
    device.throw_if_error("rtcNewScene");
    if (scene_ == nullptr) throw Error("rtcNewScene: Embree returned no scene");
}

EmbreeSceneHandle::~EmbreeSceneHandle() {
    if (scene_ != nullptr) rtcReleaseScene(scene_);
}

EmbreeSceneHandle::EmbreeSceneHandle(EmbreeSceneHandle&& other) noexcept
    : scene_(std::exchange(other.scene_, nullptr)) {}

EmbreeSceneHandle& EmbreeSceneHandle::operator=(EmbreeSceneHandle&& other) noexcept {
    if (this != &other) {
        if (scene_ != nullptr) rtcReleaseScene(scene_);
        scene_ = std::exchange(other.scene_, nullptr);
    }
    return *this;
}

}  // namespace rebraid::glue
