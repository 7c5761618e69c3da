#include "rebraid/io/gltf_animation_values.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "rebraid/core/error.h"
#include "rebraid/io/gltf_accessor.h"

namespace rebraid::gltf_animation {
namespace {

const char* type_name(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR:
            return "SCALAR";
        case TINYGLTF_TYPE_VEC2:
            return "VEC2";
        case TINYGLTF_TYPE_VEC3:
            return "VEC3";
        case TINYGLTF_TYPE_VEC4:
            return "VEC4";
        case TINYGLTF_TYPE_MAT4:
            return "MAT4";
        default:
            return "another type";
    }
}

template <typename Component>
Component load(const unsigned char* at) {
    Component value;
    std::memcpy(&value, at, sizeof value);  // glTF data need not be aligned for the host
    return value;
}

/// Component `c` of an element at `element`, decoded to float.
float decode(const unsigned char* element, int component_type, int c) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT:
            return load<float>(element + 4 * c);
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return float(element[c]) / 255.0f;
        case TINYGLTF_COMPONENT_TYPE_BYTE:
            return std::max(float(load<std::int8_t>(element + c)) / 127.0f, -1.0f);
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
            return float(load<std::uint16_t>(element + 2 * c)) / 65535.0f;
        case TINYGLTF_COMPONENT_TYPE_SHORT:
            return std::max(float(load<std::int16_t>(element + 2 * c)) / 32767.0f, -1.0f);
        default:
            return 0.0f;  // excluded by the encoding check
    }
}

bool encoding_allows(FloatEncoding encoding, const tinygltf::Accessor& accessor) {
    const int type = accessor.componentType;
    if (type == TINYGLTF_COMPONENT_TYPE_FLOAT) return true;
    if (encoding == FloatEncoding::kFloatOnly || !accessor.normalized) return false;
    const bool is_unsigned = type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                             type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
    const bool is_signed =
        type == TINYGLTF_COMPONENT_TYPE_BYTE || type == TINYGLTF_COMPONENT_TYPE_SHORT;
    return is_unsigned || (is_signed && encoding == FloatEncoding::kFloatOrNormalized);
}

const char* encoding_text(FloatEncoding encoding) {
    switch (encoding) {
        case FloatEncoding::kFloatOnly:
            return "float";
        case FloatEncoding::kFloatOrNormalized:
            return "float or normalized (unsigned) byte / short";
        default:
            return "float or normalized unsigned byte / short";
    }
}

/// The accessor after the type check; throws naming the role otherwise.
const tinygltf::Accessor& typed_accessor(const tinygltf::Model& model, int id, int type,
                                         const std::string& role, const std::string& error_prefix,
                                         GltfElementRange& range) {
    range = resolve_gltf_accessor(model, id, role, error_prefix);
    const tinygltf::Accessor& accessor = model.accessors[std::size_t(id)];
    if (accessor.type != type)
        throw Error(error_prefix + "accessor " + std::to_string(id) + " (" + role + ") is " +
                    type_name(accessor.type) + ", expected " + type_name(type));
    return accessor;
}

}  // namespace

std::vector<float> read_float_accessor(const tinygltf::Model& model, int id, int type,
                                       FloatEncoding encoding, const std::string& role,
                                       const std::string& error_prefix) {
    GltfElementRange range;
    const tinygltf::Accessor& accessor = typed_accessor(model, id, type, role, error_prefix, range);
    const std::string label = "accessor " + std::to_string(id) + " (" + role + ")";
    if (!encoding_allows(encoding, accessor))
        throw Error(
            error_prefix + label + " has component type " + std::to_string(accessor.componentType) +
            (accessor.normalized ? " (normalized)" : "") + ", expected " + encoding_text(encoding));
    const int components = tinygltf::GetNumComponentsInType(std::uint32_t(type));
    std::vector<float> values(range.count * std::uint64_t(components));
    for (std::uint64_t e = 0; e < range.count; ++e) {
        const unsigned char* element = range.first + e * range.stride;
        for (int c = 0; c < components; ++c) {
            const float value = decode(element, accessor.componentType, c);
            if (!std::isfinite(value))
                throw Error(error_prefix + label + " element " + std::to_string(e) + " component " +
                            std::to_string(c) + " is not finite");
            values[e * components + c] = value;
        }
    }
    return values;
}

std::vector<std::uint32_t> read_joint_accessor(const tinygltf::Model& model, int id, int type,
                                               const std::string& role,
                                               const std::string& error_prefix) {
    GltfElementRange range;
    const tinygltf::Accessor& accessor = typed_accessor(model, id, type, role, error_prefix, range);
    const int component_type = accessor.componentType;
    if (component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
        component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT)
        throw Error(error_prefix + "accessor " + std::to_string(id) + " (" + role +
                    ") has component type " + std::to_string(component_type) +
                    ", expected unsigned byte or unsigned short");
    const int components = tinygltf::GetNumComponentsInType(std::uint32_t(type));
    std::vector<std::uint32_t> values(range.count * std::uint64_t(components));
    for (std::uint64_t e = 0; e < range.count; ++e) {
        const unsigned char* element = range.first + e * range.stride;
        for (int c = 0; c < components; ++c)
            values[e * components + c] = component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE
                                             ? element[c]
                                             : load<std::uint16_t>(element + 2 * c);
    }
    return values;
}

}  // namespace rebraid::gltf_animation
