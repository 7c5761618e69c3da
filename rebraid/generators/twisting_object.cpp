#include "rebraid/generators/twisting_object.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <numbers>
#include <string>

#include "rebraid/core/error.h"
#include "rebraid/generators/mesh_generators.h"

namespace rebraid {

namespace {

/// The built-in object: rest positions kept aside, every pose computed from them (so poses
/// never accumulate rounding and any time can be posed in any order).
class TwistingObject final : public AnimatedObject {
public:
    explicit TwistingObject(const TwistingObjectSettings& settings) : settings_(settings) {
        Mesh mesh = make_torus_knot({.path_segment_count = settings.path_segment_count,
                                     .tube_segment_count = settings.tube_segment_count});
        mesh.name = "twisting knot";
        // Stretched along the axis, so twisting and swaying move it visibly.
        for (Vec3f& p : mesh.positions) p.y *= 4.0f;
        const BBox3f bounds = mesh.bounds();
        base_y_ = bounds.min.y;
        height_ = std::max(bounds.max.y - bounds.min.y, 1e-6f);
        radius_ = std::max(bounds.max.x - bounds.min.x, bounds.max.z - bounds.min.z) * 0.5f;
        rest_positions_ = mesh.positions;
        rest_.meshes.push_back(std::move(mesh));
        rest_.instances.push_back({0, AffineTransform::identity()});
    }

    const Scene& rest_scene() const override { return rest_; }
    float duration() const override { return settings_.period; }
    const std::vector<MeshId>& deformed_meshes() const override { return deformed_; }
    const std::vector<InstanceId>& moving_instances() const override { return moving_; }

    void pose(float time, Scene& scene) const override {
        if (scene.meshes.size() != 1 || scene.meshes[0].positions.size() != rest_positions_.size())
            throw Error("TwistingObject::pose: the scene is not a copy of the object's rest scene");
        const float phase = std::sin(2.0f * std::numbers::pi_v<float> * time / settings_.period);
        std::vector<Vec3f>& positions = scene.meshes[0].positions;
        // Every vertex is computed from its rest position alone: any thread count gives the
        // same result.
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, positions.size(), 4096),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              for (std::size_t i = range.begin(); i != range.end(); ++i)
                                  positions[i] = deform(rest_positions_[i], phase);
                          });
    }

private:
    Vec3f deform(Vec3f p, float phase) const {
        const float h = (p.y - base_y_) / height_;  // 0 at the bottom, 1 at the top
        const float angle = phase * settings_.twist_turns * 2.0f * std::numbers::pi_v<float> * h;
        const float c = std::cos(angle), s = std::sin(angle);
        const float sway = phase * settings_.sway * radius_ * h * h;
        return {c * p.x - s * p.z + sway, p.y, s * p.x + c * p.z};
    }

    TwistingObjectSettings settings_;
    Scene rest_;
    std::vector<Vec3f> rest_positions_;
    std::vector<MeshId> deformed_{0};
    std::vector<InstanceId> moving_{};
    float base_y_ = 0.0f, height_ = 1.0f, radius_ = 1.0f;
};

}  // namespace

std::unique_ptr<AnimatedObject> make_twisting_object(const TwistingObjectSettings& settings) {
    if (!(settings.period > 0.0f) || !std::isfinite(settings.period))
        throw Error("make_twisting_object: period " + std::to_string(settings.period) +
                    " must be a positive number of seconds");
    return std::make_unique<TwistingObject>(settings);
}

}  // namespace rebraid
