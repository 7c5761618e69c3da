#pragma once

// A tiny glTF writer for loader tests: builds the JSON with nlohmann::json and one binary
// buffer, and writes it as .glb (embedded BIN chunk) or .gltf + .bin into REBRAID_TEST_TMP.
// Tests edit `json` directly to produce broken files.

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rebraid/core/types.h"
#include "support/cli_runner.h"

namespace rebraid::test {

inline constexpr int kUnsignedByte = 5121;
inline constexpr int kUnsignedShort = 5123;
inline constexpr int kUnsignedInt = 5125;
inline constexpr int kFloat = 5126;

/// Path of `name` in the running test's own scratch folder (test_scratch_dir): ctest runs
/// tests as parallel processes, and two tests writing a file of the same name must not meet
/// (one read a file the other was writing).
inline std::string scratch_path(const std::string& name) {
    return (test_scratch_dir("gltf_test") / name).string();
}

/// Writes `bytes` to scratch_path(name) and returns that path.
inline std::string write_scratch_file(const std::string& name, const std::string& bytes) {
    const std::string path = scratch_path(name);
    std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return path;
}

/// One glTF document with a single buffer under construction.
struct GltfTestFile {
    nlohmann::json json = {{"asset", {{"version", "2.0"}}}};
    std::vector<unsigned char> bin;

    /// Appends `size` bytes (padded to 4) as a new bufferView; returns its index.
    int add_view(const void* data, std::size_t size, std::size_t byte_stride = 0) {
        nlohmann::json view = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", size}};
        if (byte_stride != 0) view["byteStride"] = byte_stride;
        const auto* bytes = static_cast<const unsigned char*>(data);
        bin.insert(bin.end(), bytes, bytes + size);
        bin.resize((bin.size() + 3) / 4 * 4, 0);
        return append("bufferViews", view);
    }
    /// Adds an accessor over bufferView `view`; returns its index.
    int add_accessor(int view, int component_type, std::uint64_t count, const std::string& type,
                     std::size_t byte_offset = 0) {
        return append("accessors", {{"bufferView", view},
                                    {"componentType", component_type},
                                    {"count", count},
                                    {"type", type},
                                    {"byteOffset", byte_offset}});
    }
    /// Tightly packed float VEC3 positions; returns the accessor index.
    int add_positions(const std::vector<Vec3f>& positions) {
        const int view = add_view(positions.data(), positions.size() * sizeof(Vec3f));
        return add_accessor(view, kFloat, positions.size(), "VEC3");
    }
    /// Indices stored as `component_type` (unsigned byte, short or int); returns the accessor.
    int add_indices(const std::vector<std::uint32_t>& indices, int component_type = kUnsignedInt) {
        const std::size_t size = component_type == kUnsignedByte    ? 1
                                 : component_type == kUnsignedShort ? 2
                                                                    : 4;
        std::vector<unsigned char> bytes(indices.size() * size);
        for (std::size_t i = 0; i < indices.size(); ++i)
            std::memcpy(&bytes[i * size], &indices[i], size);  // little-endian host
        return add_accessor(add_view(bytes.data(), bytes.size()), component_type, indices.size(),
                            "SCALAR");
    }
    /// Adds a mesh made of `primitives` (see primitive()); returns its index.
    int add_mesh(const std::vector<nlohmann::json>& primitives, const std::string& name = "") {
        return append("meshes", {{"primitives", primitives}, {"name", name}});
    }
    int add_node(const nlohmann::json& node) { return append("nodes", node); }
    int add_scene(const std::vector<int>& roots) { return append("scenes", {{"nodes", roots}}); }

    /// Writes a .glb; returns its path.
    std::string write_glb(const std::string& name) const {
        std::string json_text = finished_json("").dump();
        json_text.resize((json_text.size() + 3) / 4 * 4, ' ');
        const bool has_bin = !bin.empty();
        const std::uint32_t length =
            std::uint32_t(12 + 8 + json_text.size() + (has_bin ? 8 + bin.size() : 0));
        std::string out;
        auto put_u32 = [&](std::uint32_t v) { out.append(reinterpret_cast<char*>(&v), 4); };
        out += "glTF";
        put_u32(2);
        put_u32(length);
        put_u32(std::uint32_t(json_text.size()));
        put_u32(0x4E4F534A);  // "JSON"
        out += json_text;
        if (has_bin) {
            put_u32(std::uint32_t(bin.size()));
            put_u32(0x004E4942);  // "BIN\0"
            out.append(reinterpret_cast<const char*>(bin.data()), bin.size());
        }
        return write_scratch_file(name, out);
    }
    /// Writes `name` (a .gltf) with its buffer in `name`.bin beside it; returns the path.
    std::string write_gltf(const std::string& name) const {
        const std::string bin_path =
            write_scratch_file(name + ".bin", std::string(bin.begin(), bin.end()));
        const std::string bin_uri = std::filesystem::path(bin_path).filename().string();
        return write_scratch_file(name, finished_json(bin_uri).dump());
    }

private:
    int append(const char* array, const nlohmann::json& item) {
        json[array].push_back(item);
        return int(json[array].size()) - 1;
    }
    /// The document with its buffer entry added (unless a test wrote its own).
    nlohmann::json finished_json(const std::string& bin_uri) const {
        nlohmann::json out = json;
        if (!bin.empty() && !out.contains("buffers")) {
            out["buffers"] = nlohmann::json::array({nlohmann::json{{"byteLength", bin.size()}}});
            if (!bin_uri.empty()) out["buffers"][0]["uri"] = bin_uri;
        }
        return out;
    }
};

/// A primitive using accessor `position` and optional `indices` (-1 = non-indexed).
inline nlohmann::json primitive(int position, int indices = -1, int mode = 4) {
    nlohmann::json p = {{"attributes", {{"POSITION", position}}}, {"mode", mode}};
    if (indices >= 0) p["indices"] = indices;
    return p;
}

}  // namespace rebraid::test
