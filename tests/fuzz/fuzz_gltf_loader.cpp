// libFuzzer target: the glTF loader (load_gltf_scene) on arbitrary bytes, then the materials
// and texture coordinates the renderer reads. Every input must either throw rebraid::Error or
// give a scene that passes Scene::validate() and the loader's documented limits.
//
// The container follows the content, as for a file on disk: an input starting with the
// binary glTF magic "glTF" is written as a .glb, anything else as a .gltf (JSON text), byte
// for byte. The loader reads files only (rebraid/io/gltf_scene.h has no in-memory entry
// point), so each input goes through a scratch file in a folder of this process's own, where
// relative buffer URIs find nothing but the input itself.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

#include "rebraid/core/error.h"
#include "rebraid/io/gltf_material.h"
#include "rebraid/io/gltf_scene.h"

namespace {

/// A folder of this process (parallel fuzz jobs and replays must not share one), removed at
/// exit.
const std::string& scratch_folder() {
    static const std::string folder = [] {
        const char* tmp = std::getenv("TMPDIR");
        std::string pattern = std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") +
                              "/rebraid_fuzz_gltf_XXXXXX";
        if (::mkdtemp(pattern.data()) == nullptr) {
            std::perror("fuzz_gltf_loader: mkdtemp");
            std::abort();
        }
        return pattern;
    }();
    static const bool removed_at_exit = [] {
        std::atexit([] { ::rmdir(scratch_folder().c_str()); });
        return true;
    }();
    (void)removed_at_exit;
    return folder;
}

/// True when the bytes start with the binary glTF magic (0x46546C67 little-endian).
bool has_glb_magic(const std::uint8_t* data, std::size_t size) {
    return size >= 4 && std::memcmp(data, "glTF", 4) == 0;
}

/// REBRAID_FUZZ_VERBOSE=1 prints what became of each input (a replay's debugging aid).
bool verbose() {
    static const bool on = [] {
        const char* value = std::getenv("REBRAID_FUZZ_VERBOSE");
        return value != nullptr && std::strcmp(value, "1") == 0;
    }();
    return on;
}

void load_and_check(const std::string& path) {
    // Small limits: an input may declare huge counts, but the loader must refuse them
    // before it allocates, which these limits make cheap to check.
    const rebraid::GltfLoadOptions options{.max_triangles = 1u << 20,
                                           .max_vertices = 1u << 20,
                                           .max_instances = 1u << 20,
                                           .keep_model = true};
    try {
        const rebraid::GltfLoadResult loaded = rebraid::load_gltf_scene_with_report(path, options);
        const rebraid::Scene& scene = loaded.scene;
        scene.validate();  // the loader promises a valid scene
        // What the renderer reads next: materials and base colour texture coordinates (also
        // decoded from Draco), one per vertex of each mesh that has any.
        const auto uvs =
            rebraid::read_gltf_base_colour_uvs(loaded, rebraid::read_gltf_materials(loaded));
        if (uvs.size() != scene.meshes.size()) std::abort();
        for (std::size_t m = 0; m < uvs.size(); ++m)
            if (!uvs[m].empty() && uvs[m].size() != scene.meshes[m].positions.size()) std::abort();
        if (scene.instances.empty()) std::abort();
        if (scene.mesh_triangle_count() > options.max_triangles) std::abort();
        if (scene.instances.size() > options.max_instances) std::abort();
        if (verbose())
            std::fprintf(stderr, "  loaded %s: %zu meshes, %zu instances\n", path.c_str(),
                         scene.meshes.size(), scene.instances.size());
    } catch (const rebraid::Error& error) {
        // a documented rejection
        if (verbose()) std::fprintf(stderr, "  rejected: %s\n", error.what());
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string path =
        scratch_folder() + (has_glb_magic(data, size) ? "/input.glb" : "/input.gltf");
    {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
        if (!out.flush()) {
            std::perror(("fuzz_gltf_loader: cannot write " + path).c_str());
            std::abort();
        }
    }
    load_and_check(path);
    std::remove(path.c_str());
    return 0;
}
