#include "rebraid/io/gltf_animation.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <utility>

#include "rebraid/core/error.h"
#include "rebraid/io/gltf_animation_channels.h"
#include "rebraid/io/gltf_animation_math.h"
#include "rebraid/io/gltf_animation_nodes.h"
#include "rebraid/io/gltf_gpu_instancing.h"
#include "rebraid/io/gltf_morph.h"
#include "rebraid/io/gltf_skinning.h"

namespace rebraid {

using namespace gltf_animation;

namespace gltf_animation {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

/// What one loaded glTF mesh needs to be re-posed: its rest positions, morph targets and, if
/// a skinned node uses it, per-vertex joint influences.
struct DeformSource {
    std::vector<Vec3f> base_positions;
    MorphTargets morph;         ///< target_count 0: no morph targets
    SkinInfluences influences;  ///< influence_count 0: not skinned
};

/// An instance whose mesh positions are posed by apply().
struct DeformingInstance {
    InstanceId instance = 0;
    MeshId target_mesh = 0;             ///< its Mesh in the prepared layout
    std::uint32_t source = 0;           ///< index into Data::sources
    std::uint32_t node = 0;             ///< glTF node of the instance
    std::uint32_t skin = kNone;         ///< index into Data::skins, kNone when not skinned
    std::uint32_t weight_slot = kNone;  ///< animated weights of its node, kNone when static
    std::vector<float> static_weights;  ///< the node's or mesh's weights when not animated
};

}  // namespace gltf_animation

struct GltfAnimator::Data {
    std::string error_prefix;
    GltfAnimationSettings settings;
    AnimationChannels animation;
    NodeHierarchy nodes;
    std::vector<bool> has_trs_channel;  ///< per node
    /// Nodes whose world transform changes over time, parents first.
    std::vector<std::uint32_t> dynamic_nodes;
    std::vector<std::uint32_t> weight_slot_of_node;  ///< per node: kNone or a weights slot
    std::vector<std::size_t> weight_slot_widths;

    std::vector<Skin> skins;
    std::vector<DeformSource> sources;
    std::vector<DeformingInstance> deforming;

    std::vector<std::uint32_t> instance_nodes;  ///< glTF node per instance
    std::vector<bool> instance_is_skinned;
    std::vector<bool> instance_is_hideable;  ///< per instance: some pose may hide it
    /// Mesh per instance in the loader's layout, except that an instance hidden at rest whose
    /// pose may show it has its file's mesh.
    std::vector<MeshId> loaded_mesh_ids;
    std::vector<MeshId> mesh_ids;  ///< Mesh per instance in the prepared layout
    std::size_t loaded_mesh_count = 0;
    std::vector<MeshId> copy_sources;  ///< loaded Mesh of each appended copy, in order

    std::vector<MeshId> deformed_meshes;
    std::vector<InstanceId> moving_instances;
    MeshId hidden_mesh = kNoHiddenMesh;  ///< the loader's empty mesh of hidden instances
    std::vector<InstanceId> hideable_instances;
    /// The empty mesh that hidden poses use in the prepared layout (GltfHiddenPose::
    /// empty_mesh): the loader's, else one appended after the copies (appends_hidden_mesh).
    MeshId pose_hidden_mesh = kNoHiddenMesh;
    bool appends_hidden_mesh = false;
    /// Per moving instance, its EXT_mesh_gpu_instancing element's T * R * S below its node
    /// (the identity for an instance of a node without the extension).
    std::vector<Affine3d> moving_element_transforms;
};

void GltfAnimationSettings::validate() const {
    if (animation < -1)
        throw Error("GltfAnimationSettings: animation = " + std::to_string(animation) +
                    ", expected an animation index or -1 for all");
    if (parallel_grain == 0)
        throw Error("GltfAnimationSettings: parallel_grain = 0, expected at least 1");
    if (hidden_pose != GltfHiddenPose::empty_mesh && hidden_pose != GltfHiddenPose::collapsed_mesh)
        throw Error("GltfAnimationSettings: hidden_pose = " + std::to_string(int(hidden_pose)) +
                    ", expected empty_mesh or collapsed_mesh");
}

namespace {

/// Margin over kMinInstanceDeterminant for the bound of hideable instances: the float
/// transform's determinant may round a little below the double product of the bounds.
constexpr double kHideableMargin = 2.0;

double determinant(const Affine3d& m) {
    const Vec3d& x = m.columns[0];
    const Vec3d& y = m.columns[1];
    const Vec3d& z = m.columns[2];
    return x[0] * (y[1] * z[2] - y[2] * z[1]) - y[0] * (x[1] * z[2] - x[2] * z[1]) +
           z[0] * (x[1] * y[2] - x[2] * y[1]);
}

class AnimatorBuilder {
public:
    AnimatorBuilder(const GltfLoadResult& loaded, const GltfAnimationSettings& settings)
        : loaded_(loaded), model_(*loaded.model) {
        data_.settings = settings;
        data_.error_prefix = "glTF animation" + (settings.file_label.empty()
                                                     ? std::string(": ")
                                                     : " of '" + settings.file_label + "': ");
    }

    std::unique_ptr<const GltfAnimator::Data> build() {
        const std::string& prefix = data_.error_prefix;
        data_.nodes = read_node_hierarchy(model_, prefix);
        read_channels();
        read_instances();
        assign_meshes();
        place_hidden_mesh();
        for (DeformingInstance& instance : data_.deforming) read_deformation(instance);
        collect_changing_parts();
        return std::make_unique<const GltfAnimator::Data>(std::move(data_));
    }

private:
    [[noreturn]] void fail(const std::string& what) const {
        throw Error(data_.error_prefix + what);
    }

    const std::vector<GltfPrimitiveRange>& ranges(std::size_t mesh) const {
        return loaded_.report.mesh_primitives[mesh];
    }

    void read_channels() {
        const std::size_t node_count = data_.nodes.node_count();
        const std::size_t mesh_count = model_.meshes.size();
        if (loaded_.report.mesh_primitives.size() != mesh_count)
            fail("the load report lists " + std::to_string(loaded_.report.mesh_primitives.size()) +
                 " meshes, the model has " + std::to_string(mesh_count));
        mesh_target_counts_.resize(mesh_count);
        for (std::size_t m = 0; m < mesh_count; ++m)
            mesh_target_counts_[m] = morph_target_count(model_, m, ranges(m), data_.error_prefix);
        std::vector<std::size_t> node_weight_counts(node_count, 0);
        for (std::size_t n = 0; n < node_count; ++n) {
            const int mesh = model_.nodes[n].mesh;
            if (mesh >= 0 && std::size_t(mesh) < mesh_count)
                node_weight_counts[n] = mesh_target_counts_[std::size_t(mesh)];
        }
        data_.animation = read_animation_channels(model_, data_.settings.animation,
                                                  node_weight_counts, data_.error_prefix);

        data_.has_trs_channel.assign(node_count, false);
        data_.weight_slot_of_node.assign(node_count, kNone);
        for (const AnimationChannel& channel : data_.animation.channels) {
            if (channel.path != ChannelPath::kWeights) {
                data_.has_trs_channel[channel.node] = true;
            } else if (data_.weight_slot_of_node[channel.node] == kNone) {
                data_.weight_slot_of_node[channel.node] =
                    std::uint32_t(data_.weight_slot_widths.size());
                data_.weight_slot_widths.push_back(node_weight_counts[channel.node]);
            }
        }
        data_.dynamic_nodes = nodes_below(data_.nodes, data_.has_trs_channel);
        read_scale_bounds();
    }

    /// Per node, a lower bound of |determinant| of its local transform over all times: the
    /// product of its scale channels' smallest magnitudes per axis (where two animations
    /// drive it, the smaller), else of its rest transform (rotations keep the determinant).
    void read_scale_bounds() {
        const std::size_t node_count = data_.nodes.node_count();
        std::vector<Vec3d> scale_bounds(node_count, Vec3d{-1, -1, -1});
        for (const AnimationChannel& channel : data_.animation.channels) {
            if (channel.path != ChannelPath::kScale) continue;
            const KeyframeTrack& track = data_.animation.tracks[channel.track];
            Vec3d& bound = scale_bounds[channel.node];
            for (std::size_t c = 0; c < 3; ++c) {
                const double magnitude = track.min_magnitude(c);
                bound[c] = bound[c] < 0 ? magnitude : std::min(bound[c], magnitude);
            }
        }
        node_determinant_bounds_.resize(node_count);
        for (std::size_t n = 0; n < node_count; ++n) {
            const Vec3d& bound = scale_bounds[n];
            node_determinant_bounds_[n] = bound[0] < 0
                                              ? std::fabs(determinant(data_.nodes.rest_local[n]))
                                              : bound[0] * bound[1] * bound[2];
        }
        is_dynamic_node_.assign(node_count, false);
        for (std::uint32_t n : data_.dynamic_nodes) is_dynamic_node_[n] = true;
    }

    /// True when a pose may make moving instance `i`'s transform singular: the product of the
    /// determinant bounds of its node chain and its GPU-instancing element comes near
    /// kMinInstanceDeterminant.
    bool may_hide(InstanceId i) {
        const std::uint32_t node = data_.instance_nodes[i];
        if (!is_dynamic_node_[node]) return false;
        double bound = std::fabs(determinant(element_transform(i)));
        for (std::uint32_t n = node; n != kNoParent; n = data_.nodes.parent[n])
            bound *= node_determinant_bounds_[n];
        return !(bound >= kHideableMargin * double(kMinInstanceDeterminant));
    }

    void read_instances() {
        const Scene& scene = loaded_.scene;
        const std::vector<std::uint32_t>& instance_nodes = loaded_.report.instance_node_ids;
        if (instance_nodes.size() != scene.instances.size())
            fail("the load report lists " + std::to_string(instance_nodes.size()) +
                 " instance nodes for " + std::to_string(scene.instances.size()) + " instances");
        // The loader appends one empty mesh for hidden instances.
        const bool has_hidden_mesh = loaded_.report.hidden_mesh != kNoHiddenMesh;
        if (scene.meshes.size() != model_.meshes.size() + (has_hidden_mesh ? 1 : 0))
            fail("the scene has " + std::to_string(scene.meshes.size()) + " meshes, the model " +
                 std::to_string(model_.meshes.size()));
        data_.hidden_mesh = loaded_.report.hidden_mesh;
        mesh_target_counts_.resize(scene.meshes.size(), 0);
        data_.instance_nodes = instance_nodes;
        data_.loaded_mesh_count = scene.meshes.size();
        data_.instance_is_skinned.assign(scene.instances.size(), false);
        data_.instance_is_hideable.assign(scene.instances.size(), false);
        is_deforming_.assign(scene.instances.size(), false);
        const bool collapses = data_.settings.hidden_pose == GltfHiddenPose::collapsed_mesh;
        for (InstanceId i = 0; i < scene.instances.size(); ++i) {
            const tinygltf::Node& node = model_.nodes[instance_nodes[i]];
            MeshId mesh = scene.instances[i].mesh_id;
            // Hidden at rest below an animated scale (an object that appears later): posed
            // from its own mesh like any instance a pose may hide. The loader's mesh ids are
            // the file's (gltf_scene.cpp).
            const bool shows_when_posed = mesh == data_.hidden_mesh && node.skin < 0 &&
                                          node.mesh >= 0 && is_dynamic_node_[instance_nodes[i]];
            if (shows_when_posed) mesh = MeshId(node.mesh);
            data_.loaded_mesh_ids.push_back(mesh);
            // Otherwise a hidden instance stays hidden: its empty mesh is never skinned or
            // morphed.
            const bool is_skinned = node.skin >= 0 && mesh != data_.hidden_mesh;
            data_.instance_is_skinned[i] = is_skinned;
            // A skinned instance is posed by its joints, whatever its node's transform.
            const bool is_hideable = !is_skinned && mesh != data_.hidden_mesh && may_hide(i);
            data_.instance_is_hideable[i] = is_hideable;
            if (is_hideable) data_.hideable_instances.push_back(i);
            // Collapsed hidden poses move the vertices of a Mesh of the instance's own.
            if (!is_skinned && mesh_target_counts_[mesh] == 0 && !(is_hideable && collapses))
                continue;
            is_deforming_[i] = true;
            DeformingInstance instance;
            instance.instance = i;
            instance.node = instance_nodes[i];
            instance.skin = is_skinned ? skin_index(node.skin) : kNone;
            data_.deforming.push_back(std::move(instance));
        }
    }

    std::uint32_t skin_index(int skin_id) {
        const auto [found, is_new] =
            skin_index_of_id_.try_emplace(skin_id, std::uint32_t(data_.skins.size()));
        if (is_new) data_.skins.push_back(read_skin(model_, skin_id, data_.error_prefix));
        return found->second;
    }

    /// The first deforming instance of a glTF mesh keeps that mesh unless a non-deforming
    /// instance uses it too; every other deforming instance gets a copy, appended in
    /// instance order.
    void assign_meshes() {
        data_.mesh_ids = data_.loaded_mesh_ids;
        std::vector<bool> is_taken(data_.loaded_mesh_count, false);
        for (InstanceId i = 0; i < data_.loaded_mesh_ids.size(); ++i)
            if (!is_deforming_[i])
                is_taken[data_.loaded_mesh_ids[i]] = true;  // a static user keeps the rest pose
        MeshId next_copy = MeshId(data_.loaded_mesh_count);
        for (DeformingInstance& instance : data_.deforming) {
            const MeshId mesh = data_.loaded_mesh_ids[instance.instance];
            instance.target_mesh = mesh;
            if (!is_taken[mesh]) {
                is_taken[mesh] = true;
            } else {
                instance.target_mesh = next_copy++;
                data_.copy_sources.push_back(mesh);
                data_.mesh_ids[instance.instance] = instance.target_mesh;
            }
        }
    }

    /// The empty mesh of hidden poses: the loader's, else (empty_mesh poses of hideable
    /// instances) a new one after the copies.
    void place_hidden_mesh() {
        data_.pose_hidden_mesh = data_.hidden_mesh;
        if (data_.hidden_mesh != kNoHiddenMesh || data_.hideable_instances.empty() ||
            data_.settings.hidden_pose != GltfHiddenPose::empty_mesh)
            return;
        data_.pose_hidden_mesh = MeshId(data_.loaded_mesh_count + data_.copy_sources.size());
        data_.appends_hidden_mesh = true;
    }

    DeformSource& source_of_mesh(MeshId mesh, std::uint32_t& index) {
        const auto [found, is_new] =
            source_index_of_mesh_.try_emplace(mesh, std::uint32_t(data_.sources.size()));
        index = found->second;
        if (is_new) {
            DeformSource source;
            source.base_positions = loaded_.scene.meshes[mesh].positions;
            if (mesh_target_counts_[mesh] > 0)
                source.morph = read_morph_targets(model_, mesh, ranges(mesh),
                                                  source.base_positions.size(), data_.error_prefix);
            data_.sources.push_back(std::move(source));
        }
        return data_.sources[index];
    }

    void read_deformation(DeformingInstance& instance) {
        const MeshId mesh = data_.loaded_mesh_ids[instance.instance];
        DeformSource& source = source_of_mesh(mesh, instance.source);
        const std::string node_label = "node " + std::to_string(instance.node) + " ('" +
                                       model_.nodes[instance.node].name + "')";
        if (instance.skin != kNone) {
            if (source.influences.influence_count == 0)
                source.influences = read_skin_influences(
                    model_, mesh, ranges(mesh), source.base_positions.size(), data_.error_prefix);
            const Skin& skin = data_.skins[instance.skin];
            if (source.influences.required_joint_count > skin.joints.size())
                fail(node_label + ": mesh " + std::to_string(mesh) + " uses joint " +
                     std::to_string(source.influences.required_joint_count - 1) + ", skin " +
                     std::to_string(model_.nodes[instance.node].skin) + " has " +
                     std::to_string(skin.joints.size()) + " joints");
        }
        const std::size_t target_count = source.morph.target_count;
        if (target_count == 0) return;
        instance.weight_slot = data_.weight_slot_of_node[instance.node];
        // Node weights override the mesh's default weights (glTF "Morph Targets").
        const std::vector<double>& node_weights = model_.nodes[instance.node].weights;
        if (node_weights.empty()) {
            instance.static_weights = source.morph.default_weights;
            return;
        }
        if (node_weights.size() != target_count)
            fail(node_label + " has " + std::to_string(node_weights.size()) +
                 " weights, its mesh " + std::to_string(mesh) + " has " +
                 std::to_string(target_count) + " morph targets");
        for (double weight : node_weights) {
            if (!std::isfinite(weight)) fail(node_label + " has a non-finite morph weight");
            instance.static_weights.push_back(float(weight));
        }
    }

    /// T * R * S of instance i's EXT_mesh_gpu_instancing element; the identity without one.
    Affine3d element_transform(InstanceId i) {
        const std::vector<std::uint32_t>& elements = loaded_.report.instance_gpu_elements;
        if (elements.size() != data_.instance_nodes.size())
            fail("the load report lists " + std::to_string(elements.size()) +
                 " instance elements for " + std::to_string(data_.instance_nodes.size()) +
                 " instances");
        if (elements[i] == kNotGpuInstanced) return {};
        const std::uint32_t node = data_.instance_nodes[i];
        auto [found, is_new] = gpu_instancing_of_node_.try_emplace(node);
        if (is_new)
            found->second = std::make_unique<GltfGpuInstancing>(model_, node, data_.error_prefix);
        if (elements[i] >= found->second->count())
            fail("instance " + std::to_string(i) + " names element " + std::to_string(elements[i]) +
                 " of node " + std::to_string(node) + ", which has " +
                 std::to_string(found->second->count()));
        return found->second->element(elements[i]);
    }

    void collect_changing_parts() {
        std::vector<bool> is_dynamic(data_.nodes.node_count(), false);
        for (std::uint32_t n : data_.dynamic_nodes) is_dynamic[n] = true;
        for (InstanceId i = 0; i < data_.instance_nodes.size(); ++i)
            if (is_dynamic[data_.instance_nodes[i]] && !data_.instance_is_skinned[i]) {
                data_.moving_instances.push_back(i);
                data_.moving_element_transforms.push_back(element_transform(i));
            }
        for (const DeformingInstance& instance : data_.deforming) {
            // A collapsed hidden pose moves every vertex of a hideable instance.
            bool changes =
                instance.weight_slot != kNone || data_.instance_is_hideable[instance.instance];
            if (instance.skin != kNone) {
                // Unweighted vertices follow the node itself, the rest follow the joints.
                changes = changes || is_dynamic[instance.node];
                for (std::uint32_t joint : data_.skins[instance.skin].joints)
                    changes = changes || is_dynamic[joint];
            }
            if (changes) data_.deformed_meshes.push_back(instance.target_mesh);
        }
        std::sort(data_.deformed_meshes.begin(), data_.deformed_meshes.end());
    }

    const GltfLoadResult& loaded_;
    const tinygltf::Model& model_;
    GltfAnimator::Data data_;
    std::vector<std::size_t> mesh_target_counts_;
    std::vector<double> node_determinant_bounds_;  ///< per node, see read_scale_bounds()
    std::vector<bool> is_dynamic_node_;
    std::vector<bool> is_deforming_;  ///< per instance: in data_.deforming
    std::map<int, std::uint32_t> skin_index_of_id_;
    std::map<MeshId, std::uint32_t> source_index_of_mesh_;
    std::map<std::uint32_t, std::unique_ptr<GltfGpuInstancing>> gpu_instancing_of_node_;
};

/// Node poses and morph weights at one time: the scratch state of one apply() call.
struct PoseState {
    std::vector<NodeTrs> local;
    std::vector<Affine3d> world;
    std::vector<std::vector<float>> weights;  ///< per weights slot
};

PoseState evaluate_pose(const GltfAnimator::Data& data, double time) {
    PoseState pose{data.nodes.rest_trs, data.nodes.rest_world, {}};
    for (std::size_t width : data.weight_slot_widths) pose.weights.emplace_back(width, 0.0f);
    std::vector<double> value;
    for (const AnimationChannel& channel : data.animation.channels) {
        const KeyframeTrack& track = data.animation.tracks[channel.track];
        value.resize(track.width);
        track.sample(time, value.data());
        NodeTrs& local = pose.local[channel.node];
        switch (channel.path) {
            case ChannelPath::kTranslation:
                local.translation = {value[0], value[1], value[2]};
                break;
            case ChannelPath::kRotation:
                local.rotation = {value[0], value[1], value[2], value[3]};
                break;
            case ChannelPath::kScale:
                local.scale = {value[0], value[1], value[2]};
                break;
            case ChannelPath::kWeights: {
                std::vector<float>& weights = pose.weights[data.weight_slot_of_node[channel.node]];
                for (std::size_t t = 0; t < weights.size(); ++t) weights[t] = float(value[t]);
                break;
            }
        }
    }
    // Parents come first in dynamic_nodes, so each parent's world transform is final.
    for (std::uint32_t n : data.dynamic_nodes) {
        const Affine3d local =
            data.has_trs_channel[n] ? Affine3d::from_trs(pose.local[n]) : data.nodes.rest_local[n];
        const std::uint32_t parent = data.nodes.parent[n];
        pose.world[n] = parent == kNoParent ? local : pose.world[parent] * local;
    }
    return pose;
}

/// Writes the posed positions of one deforming instance into `positions`.
void pose_instance(const GltfAnimator::Data& data, const PoseState& pose,
                   const DeformingInstance& instance, std::vector<Vec3f>& positions) {
    const DeformSource& source = data.sources[instance.source];
    const std::size_t target_count = source.morph.target_count;
    const std::vector<float>& weights = instance.weight_slot != kNone
                                            ? pose.weights[instance.weight_slot]
                                            : instance.static_weights;

    std::vector<AffineTransform> joint_matrices;
    const std::size_t influence_count = source.influences.influence_count;
    const bool is_skinned = instance.skin != kNone;
    if (is_skinned) {
        // Joint matrix = world(joint) * inverse bind matrix (glTF "Skins").
        const Skin& skin = data.skins[instance.skin];
        for (std::size_t j = 0; j < skin.joints.size(); ++j)
            joint_matrices.push_back(
                (pose.world[skin.joints[j]] * skin.inverse_bind_matrices[j]).to_float());
    }
    const AffineTransform unweighted = pose.world[instance.node].to_float();

    auto pose_range = [&](std::size_t begin, std::size_t end) {
        for (std::size_t v = begin; v < end; ++v) {
            Vec3f p = source.base_positions[v];
            if (target_count > 0)
                p = morph_vertex(p, &source.morph.deltas[v * target_count], weights.data(),
                                 target_count);
            if (is_skinned)
                p = skin_vertex(p, &source.influences.joints[v * influence_count],
                                &source.influences.weights[v * influence_count], influence_count,
                                joint_matrices.data(), unweighted);
            positions[v] = p;
        }
    };
    // Every vertex is written by exactly one task from read-only inputs: the result does not
    // depend on how TBB splits the range.
    const std::size_t vertex_count = positions.size();
    const std::size_t grain = data.settings.parallel_grain;
    if (vertex_count <= grain) return pose_range(0, vertex_count);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, vertex_count, grain),
        [&](const tbb::blocked_range<std::size_t>& r) { pose_range(r.begin(), r.end()); });
}

}  // namespace

GltfAnimator::GltfAnimator(const GltfLoadResult& loaded, const GltfAnimationSettings& settings) {
    settings.validate();
    if (!loaded.model)
        throw Error("GltfAnimator: " +
                    (settings.file_label.empty() ? "" : "'" + settings.file_label + "': ") +
                    "the load result has no model: load with GltfLoadOptions::keep_model = true");
    data_ = AnimatorBuilder(loaded, settings).build();
}

GltfAnimator::~GltfAnimator() = default;
GltfAnimator::GltfAnimator(GltfAnimator&&) noexcept = default;
GltfAnimator& GltfAnimator::operator=(GltfAnimator&&) noexcept = default;

float GltfAnimator::duration() const {
    return data_->animation.duration;
}

bool GltfAnimator::animated() const {
    return !data_->moving_instances.empty() || !data_->deformed_meshes.empty();
}

const std::vector<MeshId>& GltfAnimator::deformed_meshes() const {
    return data_->deformed_meshes;
}
const std::vector<InstanceId>& GltfAnimator::moving_instances() const {
    return data_->moving_instances;
}
const std::vector<MeshId>& GltfAnimator::mesh_ids() const {
    return data_->mesh_ids;
}
const std::vector<InstanceId>& GltfAnimator::hideable_instances() const {
    return data_->hideable_instances;
}
MeshId GltfAnimator::hidden_mesh() const {
    return data_->pose_hidden_mesh;
}
std::size_t GltfAnimator::mesh_count() const {
    return data_->loaded_mesh_count + data_->copy_sources.size() +
           (data_->appends_hidden_mesh ? 1 : 0);
}

void GltfAnimator::prepare_scene(Scene& scene) const {
    const Data& data = *data_;
    const std::string prefix = data.error_prefix + "prepare_scene: ";
    if (scene.instances.size() != data.mesh_ids.size())
        throw Error(prefix + "the scene has " + std::to_string(scene.instances.size()) +
                    " instances, the animated file has " + std::to_string(data.mesh_ids.size()));
    const bool is_loaded_layout =
        mesh_count() != data.loaded_mesh_count && scene.meshes.size() == data.loaded_mesh_count;
    if (!is_loaded_layout && scene.meshes.size() != mesh_count())
        throw Error(prefix + "the scene has " + std::to_string(scene.meshes.size()) +
                    " meshes, the animated file has " + std::to_string(data.loaded_mesh_count) +
                    " (" + std::to_string(mesh_count()) +
                    " with the copies of shared deforming meshes and the hidden poses' mesh)");
    for (InstanceId i = 0; i < scene.instances.size(); ++i) {
        const MeshId mesh = scene.instances[i].mesh_id;
        const bool is_hidden_pose = data.instance_is_hideable[i] && mesh == data.pose_hidden_mesh;
        if (mesh != data.loaded_mesh_ids[i] && mesh != data.mesh_ids[i] && !is_hidden_pose)
            throw Error(prefix + "instance " + std::to_string(i) + " uses mesh " +
                        std::to_string(mesh) + ", expected " + std::to_string(data.mesh_ids[i]));
    }
    if (is_loaded_layout) {
        scene.meshes.reserve(mesh_count());
        for (MeshId source : data.copy_sources) {
            Mesh copy = scene.meshes[source];
            copy.name += " (copy " + std::to_string(scene.meshes.size()) + ")";
            scene.meshes.push_back(std::move(copy));
        }
        if (data.appends_hidden_mesh) {
            Mesh empty;
            empty.name = "hidden";
            scene.meshes.push_back(std::move(empty));
        }
    }
    // An instance hidden by an earlier pose stays so (with the identity) until apply().
    for (InstanceId i = 0; i < scene.instances.size(); ++i)
        if (!(data.instance_is_hideable[i] && scene.instances[i].mesh_id == data.pose_hidden_mesh))
            scene.instances[i].mesh_id = data.mesh_ids[i];
    for (const DeformingInstance& instance : data.deforming) {
        const std::size_t expected = data.sources[instance.source].base_positions.size();
        const std::size_t actual = scene.meshes[instance.target_mesh].positions.size();
        if (actual != expected)
            throw Error(prefix + "mesh " + std::to_string(instance.target_mesh) + " has " +
                        std::to_string(actual) + " positions, the animated file " +
                        std::to_string(expected));
    }
}

void GltfAnimator::apply(float time, Scene& scene) const {
    const Data& data = *data_;
    if (!std::isfinite(time))
        throw Error(data.error_prefix + "apply: time " + std::to_string(time) + " is not finite");
    prepare_scene(scene);

    double t = time;
    const double duration = data.animation.duration;
    if (data.settings.loop && duration > 0 && (t < 0 || t > duration)) {
        t = std::fmod(t, duration);
        if (t < 0) t += duration;
    }
    const PoseState pose = evaluate_pose(data, t);

    // Instances this pose hides, and where each shrank to (its collapsed vertices' point).
    std::vector<std::pair<InstanceId, Vec3f>> hidden;
    const bool collapses = data.settings.hidden_pose == GltfHiddenPose::collapsed_mesh;
    for (std::size_t k = 0; k < data.moving_instances.size(); ++k) {
        const InstanceId i = data.moving_instances[k];
        Instance& instance = scene.instances[i];
        AffineTransform& transform = instance.object_to_world;
        transform =
            (pose.world[data.instance_nodes[i]] * data.moving_element_transforms[k]).to_float();
        // A hidden instance draws nothing, whatever its pose; the scene needs an invertible map.
        if (data.mesh_ids[i] == data.hidden_mesh) {
            if (is_singular_transform(transform)) transform = AffineTransform::identity();
            continue;
        }
        instance.mesh_id = data.mesh_ids[i];
        // A non-finite transform is left for Scene::validate() to report.
        if (!transform.is_finite() || !is_singular_transform(transform)) continue;
        if (!data.instance_is_hideable[i])
            throw Error(data.error_prefix + "apply: instance " + std::to_string(i) + " (node " +
                        std::to_string(data.instance_nodes[i]) + ") has a singular transform " +
                        "at time " + std::to_string(time) +
                        " s, which the bounds of its scale channels exclude");
        // Hidden as the loader hides a singular instance: never hit, its number kept.
        hidden.emplace_back(i, transform.translation);
        transform = AffineTransform::identity();
        if (!collapses) instance.mesh_id = data.pose_hidden_mesh;
    }
    for (InstanceId i = 0; i < scene.instances.size(); ++i)
        if (data.instance_is_skinned[i])  // glTF: the skinned node's own transform is ignored
            scene.instances[i].object_to_world = AffineTransform::identity();
    // Instances in parallel, and each large mesh's vertices in parallel within.
    tbb::parallel_for(std::size_t(0), data.deforming.size(), [&](std::size_t d) {
        const DeformingInstance& instance = data.deforming[d];
        pose_instance(data, pose, instance, scene.meshes[instance.target_mesh].positions);
    });
    // Collapsed: every vertex at one point, so every triangle is degenerate.
    if (collapses)
        for (const auto& [i, point] : hidden) {
            std::vector<Vec3f>& positions = scene.meshes[data.mesh_ids[i]].positions;
            std::fill(positions.begin(), positions.end(), point);
        }
}

}  // namespace rebraid
