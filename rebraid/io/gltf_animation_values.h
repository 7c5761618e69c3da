#pragma once

// Reading animation, skin and morph accessors of a parsed glTF document into plain arrays
// (internal to rebraid::io). Every read goes through resolve_gltf_accessor(), so a file
// cannot make these functions read outside its buffers.

#include <cstdint>
#include <string>
#include <vector>

namespace tinygltf {
class Model;
}

namespace rebraid::gltf_animation {

/// Which component encodings a float read accepts.
enum class FloatEncoding {
    kFloatOnly,                  ///< 32-bit floats only (sampler inputs, inverse bind matrices)
    kFloatOrNormalized,          ///< also normalized (unsigned) byte / short, mapped per the spec
    kFloatOrUnsignedNormalized,  ///< also normalized unsigned byte / short (WEIGHTS_n)
};

/// Every component of accessor `id`, element after element (count x components floats).
/// `type` is the required accessor type (TINYGLTF_TYPE_SCALAR, _VEC3, _VEC4, _MAT4).
/// Normalized integers map to [0, 1] or [-1, 1] as the glTF specification's "Animations"
/// section says (c / 255, max(c / 127, -1), ...). Throws rebraid::Error starting with
/// `error_prefix` and naming `role` for a wrong type, an encoding not in `encoding`, a
/// non-finite value, or an accessor outside its buffer.
std::vector<float> read_float_accessor(const tinygltf::Model& model, int id, int type,
                                       FloatEncoding encoding, const std::string& role,
                                       const std::string& error_prefix);

/// Every component of an unsigned byte or unsigned short accessor of `type` (JOINTS_n).
std::vector<std::uint32_t> read_joint_accessor(const tinygltf::Model& model, int id, int type,
                                               const std::string& role,
                                               const std::string& error_prefix);

}  // namespace rebraid::gltf_animation
