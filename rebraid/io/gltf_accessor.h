#pragma once

#include <tiny_gltf.h>

#include <cstdint>
#include <string>

namespace rebraid {

/// Where a glTF accessor's elements are: `count` elements, `stride` bytes apart, from `first`.
struct GltfElementRange {
    const unsigned char* first = nullptr;
    std::uint64_t count = 0;
    std::uint64_t stride = 0;
};

/// True when `count` elements of `element_size` bytes, `stride` apart, starting at `offset`,
/// fit in `length` bytes. Written with divisions so huge declared counts cannot overflow.
bool gltf_elements_fit(std::uint64_t offset, std::uint64_t count, std::uint64_t stride,
                       std::uint64_t element_size, std::uint64_t length);

/// Resolves accessor `id` of `model` to its bytes after checking that it and its bufferView lie
/// inside their buffer, so reading `count` elements is safe whatever the file declares.
/// Throws rebraid::Error starting with `error_prefix` (e.g. "scene file 'a.glb': ") and
/// naming `role` (the use, e.g. "POSITION of mesh 2 ('x') primitive 0") for a missing accessor,
/// a sparse accessor (not supported), a bad bufferView or buffer reference, or a range that
/// runs past its buffer.
GltfElementRange resolve_gltf_accessor(const tinygltf::Model& model, int id,
                                       const std::string& role, const std::string& error_prefix);

/// Component `k` of the element at `element` as a number: floats as stored, integers as
/// stored or, when `normalized`, mapped to [0, 1] (unsigned) or [-1, 1] (signed, the most
/// negative value clamped to -1), as the glTF 2.0 specification ("Accessors") defines.
/// `component_type` must be one of glTF's six component types.
double read_gltf_component(const unsigned char* element, int component_type, bool normalized,
                           int k);

}  // namespace rebraid
