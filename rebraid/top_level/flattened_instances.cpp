#include "rebraid/top_level/flattened_instances.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>

namespace rebraid {

FlattenedInstances flatten_instances(const Scene& scene, bool keeps_object_space) {
    const std::size_t count = scene.instances.size();
    std::vector<std::uint64_t> vertex_offset(count + 1, 0), triangle_offset(count + 1, 0);
    for (std::size_t i = 0; i < count; ++i) {
        const Mesh& mesh = scene.meshes[scene.instances[i].mesh_id];
        vertex_offset[i + 1] = vertex_offset[i] + mesh.positions.size();
        triangle_offset[i + 1] = triangle_offset[i] + mesh.triangles.size();
    }
    FlattenedInstances out;
    out.world.name = "world";
    out.world.positions.resize(vertex_offset.back());
    out.world.triangles.resize(triangle_offset.back());
    if (keeps_object_space) out.object.positions.resize(vertex_offset.back());
    out.instance.resize(triangle_offset.back());
    out.prim.resize(triangle_offset.back());
    tbb::parallel_for(std::size_t(0), count, [&](std::size_t i) {
        const Instance& instance = scene.instances[i];
        const Mesh& mesh = scene.meshes[instance.mesh_id];
        const auto base = std::uint32_t(vertex_offset[i]);
        for (std::size_t v = 0; v < mesh.positions.size(); ++v)
            out.world.positions[base + v] =
                instance.object_to_world.transform_point(mesh.positions[v]);
        if (keeps_object_space)
            std::copy(mesh.positions.begin(), mesh.positions.end(),
                      out.object.positions.begin() + std::ptrdiff_t(base));
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
            const std::size_t at = triangle_offset[i] + t;
            const Triangle& triangle = mesh.triangles[t];
            out.world.triangles[at] = {base + triangle[0], base + triangle[1], base + triangle[2]};
            out.instance[at] = InstanceId(i);
            out.prim[at] = PrimId(t);
        }
    });
    if (keeps_object_space) {
        out.object.name = "world (object space)";
        out.object.triangles = out.world.triangles;
    }
    return out;
}

}  // namespace rebraid
