#include "rebraid/io/gltf_dynamic_object.h"

#include <utility>

#include "rebraid/core/error.h"
#include "rebraid/io/gltf_scene.h"

namespace rebraid {

namespace {

class GltfAnimatedObject final : public AnimatedObject {
public:
    GltfAnimatedObject(GltfLoadResult loaded, const GltfAnimationSettings& settings)
        : animator_(loaded, settings) {
        rest_ = std::move(loaded.scene);
        animator_.apply(0.0f, rest_);  // also brings the scene into the animator's layout
        rest_.validate();
    }

    const Scene& rest_scene() const override { return rest_; }
    float duration() const override { return animator_.duration(); }
    void pose(float time, Scene& scene) const override { animator_.apply(time, scene); }
    const std::vector<MeshId>& deformed_meshes() const override {
        return animator_.deformed_meshes();
    }
    const std::vector<InstanceId>& moving_instances() const override {
        return animator_.moving_instances();
    }

private:
    GltfAnimator animator_;
    Scene rest_;
};

}  // namespace

std::unique_ptr<AnimatedObject> load_gltf_animated_object(const std::string& path,
                                                          const GltfAnimationSettings& settings) {
    GltfAnimationSettings labelled = settings;
    if (labelled.file_label.empty()) labelled.file_label = path;
    // AnimatedObject keeps its layout from frame to frame: a hidden pose collapses a mesh.
    labelled.hidden_pose = GltfHiddenPose::collapsed_mesh;
    GltfLoadResult loaded = load_gltf_scene_with_report(path, {.keep_model = true});
    auto object = std::make_unique<GltfAnimatedObject>(std::move(loaded), labelled);
    if (!(object->duration() > 0.0f) ||
        (object->deformed_meshes().empty() && object->moving_instances().empty()))
        throw Error("nothing in '" + path + "' is animated");
    return object;
}

}  // namespace rebraid
