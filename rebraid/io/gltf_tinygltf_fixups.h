#pragma once

// Valid glTF that tinygltf 2.7 refuses (internal to rebraid::io), and the edits to the file's
// JSON that let it through, undone on the parsed model.

#include <vector>

namespace tinygltf {
class Model;
}

namespace rebraid {

/// What fix_gltf_json_for_tinygltf() changed, for undo_gltf_json_fixes().
struct GltfJsonFixes {
    /// Draco indices accessors that had no bufferView and were given the Draco one.
    std::vector<int> accessors_without_view;
};

/// Edits the JSON of `bytes` (the whole file, a GLB when `is_binary`; its BIN chunk is kept)
/// where tinygltf 2.7 refuses valid files:
/// - a buffer that EXT_meshopt_compression marks as a fallback has no `uri` and no data
///   (decoders never read it): it gets a 3-byte embedded stand-in, so a bufferView reading it
///   without being compressed fails the loader's range check;
/// - the indices accessor of a KHR_draco_mesh_compression primitive has no bufferView (its
///   data is in the Draco stream): it gets the Draco bufferView, taken away again by
///   undo_gltf_json_fixes(), so nothing can read compressed bytes as indices.
/// Leaves `bytes` alone when the file uses neither extension or its JSON does not parse
/// (tinygltf then reports the problem).
GltfJsonFixes fix_gltf_json_for_tinygltf(std::vector<unsigned char>& bytes, bool is_binary);

/// Restores in the parsed `model` what `fixes` changed that the loader must not see.
void undo_gltf_json_fixes(const GltfJsonFixes& fixes, tinygltf::Model& model);

}  // namespace rebraid
