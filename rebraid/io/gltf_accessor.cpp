#include "rebraid/io/gltf_accessor.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <type_traits>

#include "rebraid/core/error.h"

namespace rebraid {

bool gltf_elements_fit(std::uint64_t offset, std::uint64_t count, std::uint64_t stride,
                       std::uint64_t element_size, std::uint64_t length) {
    if (offset > length) return false;
    if (count == 0) return true;
    if (element_size > length - offset) return false;
    return (count - 1) <= (length - offset - element_size) / stride;
}

GltfElementRange resolve_gltf_accessor(const tinygltf::Model& model, int id,
                                       const std::string& role, const std::string& error_prefix) {
    auto fail = [&](const std::string& what) { throw Error(error_prefix + what); };
    if (id < 0 || std::size_t(id) >= model.accessors.size())
        fail(role + " references accessor " + std::to_string(id) + ", file has " +
             std::to_string(model.accessors.size()) + " accessors");
    const tinygltf::Accessor& accessor = model.accessors[std::size_t(id)];
    const std::string label = "accessor " + std::to_string(id) + " (" + role + ")";
    if (accessor.sparse.isSparse) fail(label + " is sparse: sparse accessors not supported");
    const int component_size = tinygltf::GetComponentSizeInBytes(accessor.componentType);
    const int component_count = tinygltf::GetNumComponentsInType(accessor.type);
    if (component_size <= 0 || component_count <= 0)
        fail(label + " has an invalid component type or type");
    const std::uint64_t element_size = std::uint64_t(component_size) * component_count;
    const int view_id = accessor.bufferView;
    if (view_id < 0 || std::size_t(view_id) >= model.bufferViews.size())
        fail(label + " has no valid bufferView (bufferView " + std::to_string(view_id) +
             ", file has " + std::to_string(model.bufferViews.size()) + ")");
    const tinygltf::BufferView& view = model.bufferViews[std::size_t(view_id)];
    const std::string view_label = "bufferView " + std::to_string(view_id);
    if (view.buffer < 0 || std::size_t(view.buffer) >= model.buffers.size())
        fail(view_label + " references buffer " + std::to_string(view.buffer) + ", file has " +
             std::to_string(model.buffers.size()) + " buffers");
    const std::vector<unsigned char>& buffer = model.buffers[std::size_t(view.buffer)].data;
    if (!gltf_elements_fit(view.byteOffset, 1, 1, view.byteLength, buffer.size()))
        fail(view_label + " (byteOffset " + std::to_string(view.byteOffset) + ", byteLength " +
             std::to_string(view.byteLength) + ") runs past the end of buffer " +
             std::to_string(view.buffer) + " (" + std::to_string(buffer.size()) + " bytes)");
    const std::uint64_t stride = view.byteStride != 0 ? view.byteStride : element_size;
    if (stride < element_size)
        fail(view_label + " has byteStride " + std::to_string(stride) + ", smaller than the " +
             std::to_string(element_size) + "-byte elements of " + label);
    // Checked against the real buffer size before anything is allocated from `count`.
    if (!gltf_elements_fit(accessor.byteOffset, accessor.count, stride, element_size,
                           view.byteLength))
        fail(label + " with byteOffset " + std::to_string(accessor.byteOffset) + ", count " +
             std::to_string(accessor.count) + " and stride " + std::to_string(stride) +
             " runs past the end of " + view_label + " (" + std::to_string(view.byteLength) +
             " bytes)");
    return {buffer.data() + view.byteOffset + accessor.byteOffset, accessor.count, stride};
}

namespace {

/// The `k`-th value of type T at `element`, and its normalized value when `normalized`.
template <typename T>
double component_value(const unsigned char* element, bool normalized, int k) {
    T value;
    std::memcpy(&value, element + k * sizeof(T), sizeof value);
    if constexpr (std::is_floating_point_v<T>) {
        return value;
    } else {
        if (!normalized) return double(value);
        return std::max(double(value) / double(std::numeric_limits<T>::max()), -1.0);
    }
}

}  // namespace

double read_gltf_component(const unsigned char* element, int component_type, bool normalized,
                           int k) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE:
            return component_value<std::int8_t>(element, normalized, k);
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return component_value<std::uint8_t>(element, normalized, k);
        case TINYGLTF_COMPONENT_TYPE_SHORT:
            return component_value<std::int16_t>(element, normalized, k);
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
            return component_value<std::uint16_t>(element, normalized, k);
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
            return component_value<std::uint32_t>(element, normalized, k);
        default:
            return component_value<float>(element, normalized, k);
    }
}

}  // namespace rebraid
