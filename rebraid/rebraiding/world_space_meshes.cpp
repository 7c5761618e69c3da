#include "rebraid/rebraiding/world_space_meshes.h"

#include <algorithm>
#include <cstdint>
#include <vector>

#include <tbb/parallel_for.h>

namespace rebraid {

namespace {

/// The instances placing each mesh, in instance order.
std::vector<std::vector<InstanceId>> placements_of_each_mesh(const Scene& scene) {
    std::vector<std::vector<InstanceId>> placements(scene.meshes.size());
    for (std::size_t i = 0; i < scene.instances.size(); ++i)
        placements[scene.instances[i].mesh_id].push_back(InstanceId(i));
    return placements;
}

/// The meshes to move, by mesh id: those placed once by a transform other than the identity
/// (when asked), then those placed several times whose copies fit the budget, the fewest
/// added triangles first.
std::vector<MeshId> meshes_to_move(const Scene& scene,
                                   const std::vector<std::vector<InstanceId>>& placements,
                                   const WorldSpaceMeshSettings& settings) {
    std::vector<MeshId> moving;
    struct Shared {
        std::uint64_t added_triangles;
        MeshId mesh;
    };
    std::vector<Shared> shared;
    for (std::size_t mesh = 0; mesh < placements.size(); ++mesh) {
        const std::vector<InstanceId>& placed_by = placements[mesh];
        if (placed_by.size() == 1) {
            if (settings.single_instances &&
                scene.instances[placed_by[0]].object_to_world != AffineTransform::identity())
                moving.push_back(MeshId(mesh));
        } else if (placed_by.size() > 1) {
            shared.push_back(
                {(placed_by.size() - 1) * scene.meshes[mesh].triangles.size(), MeshId(mesh)});
        }
    }
    std::ranges::sort(shared, [](const Shared& a, const Shared& b) {
        return a.added_triangles != b.added_triangles ? a.added_triangles < b.added_triangles
                                                      : a.mesh < b.mesh;
    });
    const double budget = double(settings.copy_budget) * double(scene.mesh_triangle_count());
    std::uint64_t added = 0;
    for (const Shared& candidate : shared) {
        if (double(added + candidate.added_triangles) > budget) break;
        added += candidate.added_triangles;
        moving.push_back(candidate.mesh);
    }
    std::ranges::sort(moving);
    return moving;
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

/// One instance of a moving mesh, and its positions in world space.
struct Placement {
    MeshId mesh;
    InstanceId instance;
    std::optional<std::vector<Vec3f>> positions;
};

}  // namespace

std::optional<Scene> meshes_in_world_space(const Scene& scene,
                                           const WorldSpaceMeshSettings& settings) {
    const std::vector<std::vector<InstanceId>> placements = placements_of_each_mesh(scene);
    std::vector<Placement> moved;
    for (const MeshId mesh : meshes_to_move(scene, placements, settings))
        for (const InstanceId instance : placements[mesh])
            moved.push_back({mesh, instance, std::nullopt});
    if (moved.empty()) return std::nullopt;
    tbb::parallel_for(std::size_t(0), moved.size(), [&](std::size_t i) {
        Placement& placement = moved[i];
        placement.positions = mapped_positions(scene.meshes[placement.mesh].positions,
                                               scene.instances[placement.instance].object_to_world);
    });
    // A mesh moves only when every one of its placements mapped to finite positions.
    std::vector<char> stays(scene.meshes.size(), 1);
    for (const Placement& placement : moved) stays[placement.mesh] = 0;
    for (const Placement& placement : moved)
        if (!placement.positions) stays[placement.mesh] = 1;
    if (std::ranges::count(stays, 1) == std::ptrdiff_t(scene.meshes.size())) return std::nullopt;

    Scene world;
    world.instances = scene.instances;
    world.meshes.reserve(scene.meshes.size() + moved.size());
    for (std::size_t mesh = 0; mesh < scene.meshes.size(); ++mesh)
        if (stays[mesh])
            world.meshes.push_back(scene.meshes[mesh]);
        else
            world.meshes.emplace_back();
    // `moved` lists each mesh's placements together, in instance order: the first takes the
    // mesh's place, the others get copies after the scene's meshes.
    for (std::size_t i = 0; i < moved.size(); ++i) {
        Placement& placement = moved[i];
        if (stays[placement.mesh]) continue;
        const Mesh& source = scene.meshes[placement.mesh];
        const bool is_first = i == 0 || moved[i - 1].mesh != placement.mesh;
        Instance& instance = world.instances[placement.instance];
        if (!is_first) {
            instance.mesh_id = MeshId(world.meshes.size());
            world.meshes.emplace_back();
        }
        world.meshes[instance.mesh_id] =
            Mesh{source.name, std::move(*placement.positions), source.triangles};
        instance.object_to_world = AffineTransform::identity();
    }
    return world;
}

}  // namespace rebraid
