#include "rebraid/generators/world_space_objects.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <string>

#include "rebraid/core/error.h"

namespace rebraid {

Scene bake_instances_into_world_space(const Scene& scene, std::uint32_t instances_per_object) {
    if (instances_per_object == 0)
        throw Error("bake_instances_into_world_space: instances_per_object must be at least 1");
    const std::size_t object_count =
        (scene.instances.size() + instances_per_object - 1) / instances_per_object;
    Scene baked;
    baked.meshes.resize(object_count);
    baked.instances.resize(object_count);
    // Each object writes only its own mesh: the result does not depend on the thread count.
    tbb::parallel_for(std::size_t(0), object_count, [&](std::size_t k) {
        const std::size_t first = k * instances_per_object;
        const std::size_t last = std::min(scene.instances.size(), first + instances_per_object);
        Mesh& mesh = baked.meshes[k];
        std::uint64_t vertex_count = 0, triangle_count = 0;
        for (std::size_t i = first; i < last; ++i) {
            const Mesh& source = scene.meshes[scene.instances[i].mesh_id];
            vertex_count += source.positions.size();
            triangle_count += source.triangles.size();
        }
        if (vertex_count > std::numeric_limits<std::uint32_t>::max())
            throw Error("bake_instances_into_world_space: object " + std::to_string(k) +
                        " would have " + std::to_string(vertex_count) +
                        " vertices, more than 32-bit indices address");
        mesh.positions.reserve(vertex_count);
        mesh.triangles.reserve(triangle_count);
        const Mesh& first_source = scene.meshes[scene.instances[first].mesh_id];
        mesh.name = first_source.name + "#" + std::to_string(k);
        for (std::size_t i = first; i < last; ++i) {
            const Instance& instance = scene.instances[i];
            const Mesh& source = scene.meshes[instance.mesh_id];
            const auto base = std::uint32_t(mesh.positions.size());
            for (const Vec3f& p : source.positions)
                mesh.positions.push_back(instance.object_to_world.transform_point(p));
            for (const Triangle& t : source.triangles)
                mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
        }
        baked.instances[k] = {MeshId(k), AffineTransform::identity()};
    });
    return baked;
}

}  // namespace rebraid
