#pragma once

#include <embree3/rtcore.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "embree_glue/reference/embree_geometry.h"
#include "rebraid/core/accel.h"
#include "rebraid/core/ray.h"

namespace rebraid::glue {

/// A ray set held in Embree's own layout, for timing Embree as its applications call it:
/// rtcIntersect1 and rtcOccluded1 on rays they already hold. A query through the Accel interface
/// (EmbreeFlatAccel::intersect) also checks and converts the ray and converts the hit back:
/// on the drop-in grid's camera rays that wrapper took about 100 instructions a query beside
/// rtcIntersect1's 830, and Embree traced 0.9x as fast through it. Benchmarks time this
/// batch instead, so that they compare Embree's own queries with the project's.
class EmbreeRayBatch {
public:
    /// True when `accel` is one of Embree's reference structures (EmbreeFlatAccel,
    /// EmbreeInstancedAccel, EmbreeDynamicAccel), whose scene a batch can trace.
    static bool serves(const Accel& accel);

    /// `rays` converted for `accel`'s scene, each checked as `accel.intersect` checks it
    /// (throws rebraid::Error for a ray Embree cannot trace; an empty segment stays a miss).
    /// Throws rebraid::Error when `accel` is not served.
    EmbreeRayBatch(const Accel& accel, std::span<const Ray> rays);

    /// Closest hits of rays [begin, end): each ray is reset to its input (tfar and hit ids)
    /// and traced by rtcIntersect1 with one context for the range. Ranges traced at once
    /// from several threads must not overlap.
    void intersect(std::size_t begin, std::size_t end);

    /// Occlusion of rays [begin, end): each ray is reset to its input and traced by
    /// rtcOccluded1 (which marks an occluded ray by tfar = -inf; see is_occluded).
    void occlude(std::size_t begin, std::size_t end);

    /// Whether ray `i` was found occluded by the last occlude over it.
    bool is_occluded(std::size_t i) const {
        return rays_[i].ray.tfar == -std::numeric_limits<float>::infinity();
    }

    /// Ray `i`'s closest hit after intersect (and before an occlude over it), in the
    /// project's terms (as accel.intersect would give it).
    Hit hit(std::size_t i) const { return hit_from_embree(rays_[i], instance_id_is_inst_id_); }

    std::size_t size() const { return rays_.size(); }

private:
    RTCScene scene_ = nullptr;
    bool instance_id_is_inst_id_ = false;  ///< instanced scene: the instance is instID[0]
    std::vector<RTCRayHit> rays_;
    std::vector<float> input_tfar_;
    std::vector<std::uint8_t> is_traced_;  ///< 0 for empty segments, which Embree never sees
};

}  // namespace rebraid::glue
