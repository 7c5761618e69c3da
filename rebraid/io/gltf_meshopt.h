#pragma once

// EXT_meshopt_compression (internal to rebraid::io): bufferViews whose bytes are stored
// compressed by meshoptimizer's vertex or index codec.

#include <string>
#include <vector>

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

/// tinygltf 2.7 cannot load a buffer that EXT_meshopt_compression marks as a fallback (no
/// `uri`, no data: readers that decode never need its bytes). Gives every such buffer a
/// 3-byte embedded stand-in in the file's JSON so tinygltf accepts it; a bufferView that
/// reads the fallback without being compressed then fails the loader's range check. `bytes`
/// is the whole file, a GLB when `is_binary` (its BIN chunk is kept). Returns false and
/// leaves `bytes` alone when there is no such buffer or the JSON does not parse (tinygltf
/// then reports the problem).
bool stub_gltf_meshopt_fallback_buffers(std::vector<unsigned char>& bytes, bool is_binary);

}  // namespace rebraid
