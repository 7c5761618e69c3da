#pragma once

// EXT_meshopt_compression (internal to rebraid::io): bufferViews whose bytes are stored
// compressed by meshoptimizer's vertex or index codec.

#include <string>

namespace tinygltf {
class Model;
}

namespace rebraid {

inline constexpr const char* kGltfMeshoptCompression = "EXT_meshopt_compression";

/// Decodes every bufferView of `model` that carries EXT_meshopt_compression (modes
/// ATTRIBUTES, TRIANGLES, INDICES; filters NONE, OCTAHEDRAL, QUATERNION, EXPONENTIAL) into a
/// buffer appended to the model and points the view at it, so accessors read the decoded
/// bytes as usual. A decoded view may be at most 128 times its compressed bytes plus 64 KiB
/// (well above what the codecs reach), which stops a few bytes from claiming gigabytes.
/// Throws rebraid::Error starting with `error_prefix` naming the bufferView for a malformed
/// extension, a compressed range past its buffer, a stride or count the mode does not allow,
/// or data the codec rejects.
void decode_gltf_meshopt_views(tinygltf::Model& model, const std::string& error_prefix);

}  // namespace rebraid
