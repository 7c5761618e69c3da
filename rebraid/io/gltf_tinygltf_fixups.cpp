#include "rebraid/io/gltf_tinygltf_fixups.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>

#include "rebraid/io/gltf_draco.h"
#include "rebraid/io/gltf_meshopt.h"

namespace rebraid {
namespace {

using nlohmann::json;

std::uint32_t read_u32(const std::vector<unsigned char>& bytes, std::size_t at) {
    std::uint32_t value;
    std::memcpy(&value, bytes.data() + at, sizeof value);  // GLB is little-endian, as the host
    return value;
}

void write_u32(std::vector<unsigned char>& bytes, std::size_t at, std::uint32_t value) {
    std::memcpy(bytes.data() + at, &value, sizeof value);
}

/// `object[key]` when `object` is an object holding `key`, else null.
const json* member(const json& object, const char* key) {
    if (!object.is_object()) return nullptr;
    const auto found = object.find(key);
    return found == object.end() ? nullptr : &*found;
}

bool stub_meshopt_fallback_buffers(json& document) {
    json* buffers = document.contains("buffers") ? &document["buffers"] : nullptr;
    if (!buffers || !buffers->is_array()) return false;
    bool changed = false;
    for (json& buffer : *buffers) {
        if (!buffer.is_object() || buffer.contains("uri")) continue;
        const json* extensions = member(buffer, "extensions");
        const json* meshopt = extensions ? member(*extensions, kGltfMeshoptCompression) : nullptr;
        const json* fallback = meshopt ? member(*meshopt, "fallback") : nullptr;
        if (!fallback || *fallback != true) continue;
        buffer["uri"] = "data:application/octet-stream;base64,AAAA";  // three zero bytes
        buffer["byteLength"] = 3;
        changed = true;
    }
    return changed;
}

void give_draco_indices_a_view(json& document, GltfJsonFixes& fixes) {
    const json* meshes = member(document, "meshes");
    json* accessors = document.contains("accessors") ? &document["accessors"] : nullptr;
    if (!meshes || !meshes->is_array() || !accessors || !accessors->is_array()) return;
    for (const json& mesh : *meshes) {
        const json* primitives = member(mesh, "primitives");
        if (!primitives || !primitives->is_array()) continue;
        for (const json& primitive : *primitives) {
            const json* extensions = member(primitive, "extensions");
            const json* draco = extensions ? member(*extensions, kGltfDracoCompression) : nullptr;
            const json* view = draco ? member(*draco, "bufferView") : nullptr;
            const json* indices = member(primitive, "indices");
            if (!view || !view->is_number_unsigned() || !indices ||
                !indices->is_number_unsigned() ||
                indices->get<std::uint64_t>() >= accessors->size())
                continue;
            json& accessor = (*accessors)[indices->get<std::size_t>()];
            if (!accessor.is_object() || accessor.contains("bufferView")) continue;
            // Any valid view passes tinygltf; an invalid Draco one is reported by the decoder.
            const json* views = member(document, "bufferViews");
            const std::size_t view_count = views && views->is_array() ? views->size() : 0;
            if (view_count == 0) continue;
            accessor["bufferView"] = view->get<std::uint64_t>() < view_count ? *view : json(0);
            fixes.accessors_without_view.push_back(indices->get<int>());
        }
    }
}

}  // namespace

GltfJsonFixes fix_gltf_json_for_tinygltf(std::vector<unsigned char>& bytes, bool is_binary) {
    GltfJsonFixes fixes;
    // GLB: 12-byte header, then the JSON chunk (length, type, text); its layout was checked.
    const std::size_t json_begin = is_binary ? 20 : 0;
    if (bytes.size() < json_begin) return fixes;
    const std::size_t json_size = is_binary ? read_u32(bytes, 12) : bytes.size();
    const auto json_first = bytes.begin() + std::ptrdiff_t(json_begin);
    const auto json_last = json_first + std::ptrdiff_t(json_size);
    auto mentions = [&](const std::string& name) {
        return std::search(json_first, json_last, name.begin(), name.end()) != json_last;
    };
    if (!mentions(kGltfMeshoptCompression) && !mentions(kGltfDracoCompression)) return fixes;
    json document = json::parse(json_first, json_last, nullptr, false);
    if (document.is_discarded() || !document.is_object()) return fixes;
    const bool stubbed = stub_meshopt_fallback_buffers(document);
    give_draco_indices_a_view(document, fixes);
    if (!stubbed && fixes.accessors_without_view.empty()) return fixes;

    std::string text = document.dump();
    if (!is_binary) {
        bytes.assign(text.begin(), text.end());
        return fixes;
    }
    text.resize((text.size() + 3) / 4 * 4, ' ');
    std::vector<unsigned char> rebuilt(bytes.begin(), bytes.begin() + 20);
    rebuilt.insert(rebuilt.end(), text.begin(), text.end());
    rebuilt.insert(rebuilt.end(), json_last, bytes.end());  // the BIN chunk, if any
    write_u32(rebuilt, 8, std::uint32_t(rebuilt.size()));
    write_u32(rebuilt, 12, std::uint32_t(text.size()));
    bytes = std::move(rebuilt);
    return fixes;
}

void undo_gltf_json_fixes(const GltfJsonFixes& fixes, tinygltf::Model& model) {
    for (int id : fixes.accessors_without_view)
        if (id >= 0 && std::size_t(id) < model.accessors.size())
            model.accessors[std::size_t(id)].bufferView = -1;
}

}  // namespace rebraid
