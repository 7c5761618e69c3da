#pragma once

// Keyframe tracks and channels of glTF animations (internal to rebraid::io): reading them
// from a parsed document with every check the animator promises, and sampling them at a time
// per the glTF 2.0 specification (appendix "Interpolation").

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace tinygltf {
class Model;
}

namespace rebraid::gltf_animation {

enum class Interpolation { kStep, kLinear, kCubicSpline };

/// The node property a channel drives.
enum class ChannelPath { kTranslation, kRotation, kScale, kWeights };

/// One sampler: key times and output values, `width` floats per value (3 for translation and
/// scale, 4 for rotation, the morph target count for weights). CUBICSPLINE stores three
/// values per key: in-tangent, value, out-tangent.
struct KeyframeTrack {
    std::vector<float> times;   ///< strictly increasing, at least one
    std::vector<float> values;  ///< times.size() x (3 if cubic else 1) x width
    std::size_t width = 0;
    Interpolation interpolation = Interpolation::kLinear;
    bool is_rotation = false;  ///< quaternion values: slerp, and unit length results

    /// The track's value at `time` into out[0, width): clamped to the first / last key
    /// outside the keys; rotations are unit quaternions.
    void sample(double time, double* out) const;
    /// A lower bound of |component `c`| of sample() over all times: 0 when the component may
    /// reach zero (a key of 0, a sign change between keys, a spline that may dip to 0).
    /// Meant for scale tracks (not rotations, whose samples are normalized).
    double min_magnitude(std::size_t c) const;
};

/// A channel: which node property is driven by which track.
struct AnimationChannel {
    std::uint32_t node = 0;
    ChannelPath path = ChannelPath::kTranslation;
    std::uint32_t track = 0;  ///< index into AnimationChannels::tracks
};

/// The channels of the played animation(s), in file order (later channels win).
struct AnimationChannels {
    std::vector<KeyframeTrack> tracks;
    std::vector<AnimationChannel> channels;
    float duration = 0;  ///< latest key time over all channels
};

/// Reads animation `animation` of `model` (-1: all animations). `node_weight_counts[n]` is the
/// number of morph weights of node n (its mesh's target count, 0 without one). Throws
/// rebraid::Error starting with `error_prefix`, naming the animation, channel and problem: an
/// animation index out of range, a missing node or sampler, an unknown path or
/// interpolation, a node with a matrix (only TRS nodes may be animated), weights for a node
/// without morph targets, sampler inputs that are empty, non-finite or not strictly
/// increasing, outputs of the wrong type or count.
AnimationChannels read_animation_channels(const tinygltf::Model& model, int animation,
                                          const std::vector<std::size_t>& node_weight_counts,
                                          const std::string& error_prefix);

}  // namespace rebraid::gltf_animation
