// libFuzzer target: the glTF loader (load_gltf_scene) on arbitrary bytes, as .glb and as
// .gltf. Every input must either throw rebraid::Error or give a scene that passes
// Scene::validate() and the loader's documented limits.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>

#include "rebraid/core/error.h"
#include "rebraid/io/gltf_scene.h"

namespace {

/// A scratch file of this process (parallel fuzz jobs must not share one).
std::string scratch_path(const char* extension) {
    const char* dir = std::getenv("TMPDIR");
    return std::string(dir != nullptr ? dir : "/tmp") + "/rebraid_fuzz_gltf_" +
           std::to_string(::getpid()) + extension;
}

void load_and_check(const std::uint8_t* data, std::size_t size, const char* extension) {
    const std::string path = scratch_path(extension);
    std::ofstream(path, std::ios::binary | std::ios::trunc)
        .write(reinterpret_cast<const char*>(data), std::streamsize(size));
    // Small limits: an input may declare huge counts, but the loader must refuse them
    // before it allocates, which these limits make cheap to check.
    const rebraid::GltfLoadOptions options{.max_triangles = 1u << 20, .max_vertices = 1u << 20};
    try {
        const rebraid::Scene scene = rebraid::load_gltf_scene(path, options);
        scene.validate();  // the loader promises a valid scene
        if (scene.instances.empty()) std::abort();
        if (scene.mesh_triangle_count() > options.max_triangles) std::abort();
    } catch (const rebraid::Error&) {
        // a documented rejection
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    // The first byte picks the container so one corpus explores both parsers; .glb files
    // start with "glTF", which the loader recognises whatever the extension.
    if (size == 0) return 0;
    load_and_check(data + 1, size - 1, (data[0] & 1) != 0 ? ".glb" : ".gltf");
    return 0;
}
