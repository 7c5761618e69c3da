#include "rebraid/io/gltf_gpu_instancing.h"

#include <cmath>

#include "rebraid/core/error.h"

namespace rebraid {
namespace {

/// |q| may differ from 1 by this much: the glTF validator's unit-length tolerance, which
/// normalized 8-bit rotations also meet. The quaternion is normalized before use.
constexpr double kUnitLengthTolerance = 0.00769;

}  // namespace

bool GltfGpuInstancing::is_used_by(const tinygltf::Model& model, std::size_t node) {
    return model.nodes[node].extensions.count(kGltfGpuInstancing) != 0;
}

void GltfGpuInstancing::fail(const std::string& what) const {
    throw Error(error_prefix_ + node_label_ + " " + kGltfGpuInstancing + ": " + what);
}

GltfGpuInstancing::GltfGpuInstancing(const tinygltf::Model& model, std::size_t node,
                                     const std::string& error_prefix)
    : error_prefix_(error_prefix),
      node_label_("node " + std::to_string(node) + " ('" + model.nodes[node].name + "')") {
    const tinygltf::Value& extension = model.nodes[node].extensions.at(kGltfGpuInstancing);
    if (model.nodes[node].mesh < 0) fail("the node has no mesh to instance");
    if (!extension.IsObject() || !extension.Has("attributes") ||
        !extension.Get("attributes").IsObject())
        fail("needs an 'attributes' object");
    const tinygltf::Value& attributes = extension.Get("attributes");
    for (const std::string& name : attributes.Keys())
        if (name != "TRANSLATION" && name != "ROTATION" && name != "SCALE" && name[0] != '_')
            fail("unknown attribute '" + name + "'");
    translation_ = read_attribute(model, attributes, "TRANSLATION", TINYGLTF_TYPE_VEC3, false);
    rotation_ = read_attribute(model, attributes, "ROTATION", TINYGLTF_TYPE_VEC4, true);
    scale_ = read_attribute(model, attributes, "SCALE", TINYGLTF_TYPE_VEC3, false);
    if (!has_count_) fail("needs a TRANSLATION, ROTATION or SCALE attribute");
    if (count_ == 0) fail("the attributes have a count of zero");
}

GltfGpuInstancing::Attribute GltfGpuInstancing::read_attribute(const tinygltf::Model& model,
                                                               const tinygltf::Value& attributes,
                                                               const char* name, int type,
                                                               bool allow_normalized_integers) {
    Attribute attribute;
    if (!attributes.Has(name)) return attribute;
    const tinygltf::Value& id = attributes.Get(name);
    if (!id.IsInt()) fail(std::string(name) + " is not an accessor index");
    const std::string role = std::string(name) + " of " + node_label_ + " " + kGltfGpuInstancing;
    attribute.range = resolve_gltf_accessor(model, id.GetNumberAsInt(), role, error_prefix_);
    const tinygltf::Accessor& accessor = model.accessors[std::size_t(id.GetNumberAsInt())];
    attribute.component_type = accessor.componentType;
    attribute.normalized = accessor.normalized;
    const bool is_float = accessor.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT;
    const bool is_normalized_integer =
        accessor.normalized && (accessor.componentType == TINYGLTF_COMPONENT_TYPE_BYTE ||
                                accessor.componentType == TINYGLTF_COMPONENT_TYPE_SHORT);
    if (accessor.type != type ||
        !(is_float || (allow_normalized_integers && is_normalized_integer)))
        fail(std::string(name) + " must be a " +
             (allow_normalized_integers ? "float or normalized byte or short VEC4" : "float VEC3") +
             " accessor");
    if (has_count_ && attribute.range.count != count_)
        fail(std::string(name) + " has " + std::to_string(attribute.range.count) +
             " elements, the other attributes " + std::to_string(count_));
    count_ = attribute.range.count;
    has_count_ = true;
    return attribute;
}

gltf_animation::Vec3d GltfGpuInstancing::vec3(const Attribute& attribute, std::uint64_t i,
                                              const char* name) const {
    const unsigned char* element = attribute.range.first + i * attribute.range.stride;
    gltf_animation::Vec3d value{};
    for (int k = 0; k < 3; ++k) {
        value[std::size_t(k)] =
            read_gltf_component(element, attribute.component_type, attribute.normalized, k);
        if (!std::isfinite(value[std::size_t(k)]))
            fail(std::string(name) + " of instance " + std::to_string(i) + " is not finite");
    }
    return value;
}

gltf_animation::Affine3d GltfGpuInstancing::element(std::uint64_t i) const {
    gltf_animation::NodeTrs trs;
    if (translation_.range.first) trs.translation = vec3(translation_, i, "TRANSLATION");
    if (scale_.range.first) trs.scale = vec3(scale_, i, "SCALE");
    if (rotation_.range.first) {
        const unsigned char* element = rotation_.range.first + i * rotation_.range.stride;
        double q[4];
        for (int k = 0; k < 4; ++k)
            q[k] = read_gltf_component(element, rotation_.component_type, rotation_.normalized, k);
        const double length = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (!(std::fabs(length - 1) <= kUnitLengthTolerance))
            fail("ROTATION of instance " + std::to_string(i) +
                 " is not a unit quaternion (length " + std::to_string(length) + ")");
        trs.rotation = gltf_animation::Quatd{q[0], q[1], q[2], q[3]}.normalized();
    }
    return gltf_animation::Affine3d::from_trs(trs);
}

}  // namespace rebraid
