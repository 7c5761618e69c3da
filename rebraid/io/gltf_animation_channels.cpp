#include "rebraid/io/gltf_animation_channels.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "rebraid/core/error.h"
#include "rebraid/io/gltf_animation_math.h"
#include "rebraid/io/gltf_animation_values.h"

namespace rebraid::gltf_animation {

void KeyframeTrack::sample(double time, double* out) const {
    const bool is_cubic = interpolation == Interpolation::kCubicSpline;
    const std::size_t values_per_key = is_cubic ? 3 : 1;
    // Part 0 / 1 / 2 of a cubic key: in-tangent, value, out-tangent.
    auto at = [&](std::size_t key, std::size_t part) {
        return values.data() + (key * values_per_key + (is_cubic ? part : 0)) * width;
    };
    auto copy_value = [&](std::size_t key) {
        const float* value = at(key, 1);
        for (std::size_t c = 0; c < width; ++c) out[c] = value[c];
    };
    const std::size_t key_count = times.size();
    if (key_count == 1 || time <= times.front()) return copy_value(0);
    if (time >= times.back()) return copy_value(key_count - 1);

    // times[k] <= time < times[k + 1]
    const std::size_t k =
        std::size_t(std::upper_bound(times.begin(), times.end(), time) - times.begin()) - 1;
    const double key_delta = double(times[k + 1]) - double(times[k]);
    const double s = (time - double(times[k])) / key_delta;
    switch (interpolation) {
        case Interpolation::kStep:
            return copy_value(k);
        case Interpolation::kLinear: {
            const float* a = at(k, 1);
            const float* b = at(k + 1, 1);
            if (is_rotation) {
                const Quatd q = slerp({a[0], a[1], a[2], a[3]}, {b[0], b[1], b[2], b[3]}, s);
                out[0] = q.x, out[1] = q.y, out[2] = q.z, out[3] = q.w;
                return;
            }
            for (std::size_t c = 0; c < width; ++c) out[c] = (1 - s) * a[c] + s * b[c];
            return;
        }
        case Interpolation::kCubicSpline: {
            // Hermite spline: p(s) = (2s^3 - 3s^2 + 1) v_k + td (s^3 - 2s^2 + s) b_k
            //                      + (-2s^3 + 3s^2) v_k+1 + td (s^3 - s^2) a_k+1
            const double s2 = s * s, s3 = s2 * s;
            const double value_k = 2 * s3 - 3 * s2 + 1, value_next = -2 * s3 + 3 * s2;
            const double out_tangent_k = key_delta * (s3 - 2 * s2 + s);
            const double in_tangent_next = key_delta * (s3 - s2);
            const float* v0 = at(k, 1);
            const float* b0 = at(k, 2);
            const float* v1 = at(k + 1, 1);
            const float* a1 = at(k + 1, 0);
            for (std::size_t c = 0; c < width; ++c)
                out[c] = value_k * v0[c] + out_tangent_k * b0[c] + value_next * v1[c] +
                         in_tangent_next * a1[c];
            if (is_rotation) {
                const Quatd q = Quatd{out[0], out[1], out[2], out[3]}.normalized();
                out[0] = q.x, out[1] = q.y, out[2] = q.z, out[3] = q.w;
            }
            return;
        }
    }
}

double KeyframeTrack::min_magnitude(std::size_t c) const {
    const bool is_cubic = interpolation == Interpolation::kCubicSpline;
    const std::size_t values_per_key = is_cubic ? 3 : 1;
    auto at = [&](std::size_t key, std::size_t part) {
        return double(values[(key * values_per_key + (is_cubic ? part : 0)) * width + c]);
    };
    // Outside the keys the samples clamp to the first and last key values.
    double bound = std::fabs(at(0, 1));
    for (std::size_t k = 0; k + 1 < times.size(); ++k) {
        const double a = at(k, 1), b = at(k + 1, 1);
        if (interpolation == Interpolation::kStep) {  // holds each key's value
            bound = std::min(bound, std::fabs(b));
            continue;
        }
        // Between two keys of one sign LINEAR stays between them; else it crosses zero.
        if (!((a > 0 && b > 0) || (a < 0 && b < 0))) return 0;
        double segment = std::min(std::fabs(a), std::fabs(b));
        if (is_cubic) {
            // The Hermite weights of the two values are in [0, 1] and sum to 1; those of the
            // tangents (times the key interval) stay within 4/27 in magnitude.
            const double key_delta = double(times[k + 1]) - double(times[k]);
            segment -= 4.0 / 27.0 * key_delta * (std::fabs(at(k, 2)) + std::fabs(at(k + 1, 0)));
        }
        if (!(segment > 0)) return 0;
        bound = std::min(bound, segment);
    }
    return bound;
}

namespace {

class ChannelReader {
public:
    ChannelReader(const tinygltf::Model& model, const std::vector<std::size_t>& node_weight_counts,
                  const std::string& error_prefix)
        : model_(model), node_weight_counts_(node_weight_counts), error_prefix_(error_prefix) {}

    void read_animation(std::size_t a) {
        const tinygltf::Animation& animation = model_.animations[a];
        const std::string label = "animation " + std::to_string(a) + " ('" + animation.name + "')";
        track_of_sampler_.clear();
        for (std::size_t c = 0; c < animation.channels.size(); ++c)
            read_channel(animation, label + " channel " + std::to_string(c), c);
    }

    AnimationChannels result;

private:
    [[noreturn]] void fail(const std::string& what) const { throw Error(error_prefix_ + what); }

    void read_channel(const tinygltf::Animation& animation, const std::string& label,
                      std::size_t c) {
        const tinygltf::AnimationChannel& channel = animation.channels[c];
        // glTF: a channel without a target node (set by an extension) is ignored.
        if (channel.target_node < 0) return;
        const std::size_t node = std::size_t(channel.target_node);
        if (node >= model_.nodes.size())
            fail(label + " targets missing node " + std::to_string(node) + ", file has " +
                 std::to_string(model_.nodes.size()) + " nodes");
        const std::string node_label =
            "node " + std::to_string(node) + " ('" + model_.nodes[node].name + "')";
        if (!model_.nodes[node].matrix.empty())
            fail(label + " animates " + node_label +
                 ", which has a matrix: glTF animates only nodes given by TRS");

        ChannelPath path;
        std::size_t width = 0;
        const std::string& path_name = channel.target_path;
        if (path_name == "translation") {
            path = ChannelPath::kTranslation, width = 3;
        } else if (path_name == "rotation") {
            path = ChannelPath::kRotation, width = 4;
        } else if (path_name == "scale") {
            path = ChannelPath::kScale, width = 3;
        } else if (path_name == "weights") {
            path = ChannelPath::kWeights, width = node_weight_counts_[node];
            if (width == 0)
                fail(label + " animates the weights of " + node_label +
                     ", which has no mesh with morph targets");
        } else {
            fail(label + " has an unknown target path '" + path_name + "'");
        }

        if (channel.sampler < 0 || std::size_t(channel.sampler) >= animation.samplers.size())
            fail(label + " references sampler " + std::to_string(channel.sampler) +
                 ", the animation has " + std::to_string(animation.samplers.size()) + " samplers");
        const std::size_t sampler = std::size_t(channel.sampler);
        const std::map<std::size_t, TrackKey>::const_iterator cached =
            track_of_sampler_.find(sampler);
        std::uint32_t track = 0;
        if (cached != track_of_sampler_.end() && cached->second.width == width &&
            cached->second.is_rotation == (path == ChannelPath::kRotation)) {
            track = cached->second.track;
        } else {
            track = std::uint32_t(result.tracks.size());
            result.tracks.push_back(read_track(animation.samplers[sampler],
                                               label + " (sampler " + std::to_string(sampler) + ")",
                                               path, width));
            track_of_sampler_[sampler] = {track, width, path == ChannelPath::kRotation};
        }
        result.duration = std::max(result.duration, result.tracks[track].times.back());
        result.channels.push_back({std::uint32_t(node), path, track});
    }

    KeyframeTrack read_track(const tinygltf::AnimationSampler& sampler, const std::string& label,
                             ChannelPath path, std::size_t width) const {
        KeyframeTrack track;
        track.width = width;
        track.is_rotation = path == ChannelPath::kRotation;
        const std::string& interpolation = sampler.interpolation;
        if (interpolation.empty() || interpolation == "LINEAR")
            track.interpolation = Interpolation::kLinear;
        else if (interpolation == "STEP")
            track.interpolation = Interpolation::kStep;
        else if (interpolation == "CUBICSPLINE")
            track.interpolation = Interpolation::kCubicSpline;
        else
            fail(label + " has an unknown interpolation '" + interpolation + "'");

        track.times =
            read_float_accessor(model_, sampler.input, TINYGLTF_TYPE_SCALAR,
                                FloatEncoding::kFloatOnly, "input of " + label, error_prefix_);
        if (track.times.empty()) fail(label + " has no keys (its input accessor is empty)");
        for (std::size_t k = 1; k < track.times.size(); ++k)
            if (!(track.times[k] > track.times[k - 1]))
                fail(label + ": input times are not strictly increasing (key " +
                     std::to_string(k - 1) + " at " + std::to_string(track.times[k - 1]) +
                     " s, key " + std::to_string(k) + " at " + std::to_string(track.times[k]) +
                     " s)");

        const bool is_weights = path == ChannelPath::kWeights;
        const int output_type = is_weights                       ? TINYGLTF_TYPE_SCALAR
                                : path == ChannelPath::kRotation ? TINYGLTF_TYPE_VEC4
                                                                 : TINYGLTF_TYPE_VEC3;
        const FloatEncoding encoding = is_weights || track.is_rotation
                                           ? FloatEncoding::kFloatOrNormalized
                                           : FloatEncoding::kFloatOnly;
        track.values = read_float_accessor(model_, sampler.output, output_type, encoding,
                                           "output of " + label, error_prefix_);
        const std::size_t values_per_key =
            track.interpolation == Interpolation::kCubicSpline ? 3 : 1;
        const std::size_t expected = track.times.size() * values_per_key * width;
        if (track.values.size() != expected)
            fail(label + ": output has " + std::to_string(track.values.size()) +
                 " numbers, expected " + std::to_string(expected) + " (" +
                 std::to_string(track.times.size()) + " keys x " + std::to_string(values_per_key) +
                 " x " + std::to_string(width) + ")");
        return track;
    }

    struct TrackKey {
        std::uint32_t track = 0;
        std::size_t width = 0;
        bool is_rotation = false;
    };

    const tinygltf::Model& model_;
    const std::vector<std::size_t>& node_weight_counts_;
    const std::string& error_prefix_;
    std::map<std::size_t, TrackKey> track_of_sampler_;  // samplers shared by channels
};

}  // namespace

AnimationChannels read_animation_channels(const tinygltf::Model& model, int animation,
                                          const std::vector<std::size_t>& node_weight_counts,
                                          const std::string& error_prefix) {
    const std::size_t animation_count = model.animations.size();
    const bool in_range = animation == -1 ||
                          (animation >= 0 && std::size_t(animation) < animation_count) ||
                          (animation == 0 && animation_count == 0);
    if (!in_range)
        throw Error(error_prefix + "animation " + std::to_string(animation) +
                    " does not exist, file has " + std::to_string(animation_count) +
                    " animations (use -1 for all)");
    ChannelReader reader(model, node_weight_counts, error_prefix);
    for (std::size_t a = 0; a < animation_count; ++a)
        if (animation == -1 || std::size_t(animation) == a) reader.read_animation(a);
    return std::move(reader.result);
}

}  // namespace rebraid::gltf_animation
