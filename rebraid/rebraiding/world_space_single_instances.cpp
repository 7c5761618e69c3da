#include "rebraid/rebraiding/world_space_single_instances.h"

#include <algorithm>
#include <cstdint>
#include <vector>

#include <tbb/parallel_for.h>

namespace rebraid {

namespace {

/// The instance placing each mesh when exactly one does (kInvalidId otherwise).
std::vector<InstanceId> sole_instance_of_each_mesh(const Scene& scene) {
    std::vector<std::uint32_t> uses(scene.meshes.size(), 0);
    std::vector<InstanceId> sole(scene.meshes.size(), kInvalidId);
    for (std::size_t i = 0; i < scene.instances.size(); ++i) {
        const MeshId mesh = scene.instances[i].mesh_id;
        if (++uses[mesh] == 1) sole[mesh] = InstanceId(i);
    }
    for (std::size_t mesh = 0; mesh < uses.size(); ++mesh)
        if (uses[mesh] != 1) sole[mesh] = kInvalidId;
    return sole;
}

/// `positions` mapped by `to_world`, or nullopt when a mapped position is not finite.
std::optional<std::vector<Vec3f>> mapped_positions(const std::vector<Vec3f>& positions,
                                                   const AffineTransform& to_world) {
    std::vector<Vec3f> mapped(positions.size());
    for (std::size_t i = 0; i < positions.size(); ++i) {
        mapped[i] = to_world.transform_point(positions[i]);
        if (!is_finite(mapped[i])) return std::nullopt;
    }
    return mapped;
}

}  // namespace

std::optional<Scene> single_instances_in_world_space(const Scene& scene) {
    const std::vector<InstanceId> sole = sole_instance_of_each_mesh(scene);
    std::vector<MeshId> moving;
    for (std::size_t mesh = 0; mesh < sole.size(); ++mesh)
        if (sole[mesh] != kInvalidId &&
            !(scene.instances[sole[mesh]].object_to_world == AffineTransform::identity()))
            moving.push_back(MeshId(mesh));
    if (moving.empty()) return std::nullopt;

    std::vector<std::optional<std::vector<Vec3f>>> mapped(moving.size());
    tbb::parallel_for(std::size_t(0), moving.size(), [&](std::size_t i) {
        const MeshId mesh = moving[i];
        mapped[i] = mapped_positions(scene.meshes[mesh].positions,
                                     scene.instances[sole[mesh]].object_to_world);
    });
    std::vector<std::size_t> mapped_of_mesh(scene.meshes.size(), moving.size());
    for (std::size_t i = 0; i < moving.size(); ++i)
        if (mapped[i]) mapped_of_mesh[moving[i]] = i;
    if (std::ranges::count(mapped_of_mesh, moving.size()) == std::ptrdiff_t(scene.meshes.size()))
        return std::nullopt;
    Scene world;
    world.instances = scene.instances;
    world.meshes.reserve(scene.meshes.size());
    for (std::size_t mesh = 0; mesh < scene.meshes.size(); ++mesh) {
        const std::size_t i = mapped_of_mesh[mesh];
        if (i == moving.size()) {
            world.meshes.push_back(scene.meshes[mesh]);
            continue;
        }
        world.meshes.push_back(
            Mesh{scene.meshes[mesh].name, std::move(*mapped[i]), scene.meshes[mesh].triangles});
        world.instances[sole[mesh]].object_to_world = AffineTransform::identity();
    }
    return world;
}

}  // namespace rebraid
