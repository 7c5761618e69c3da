#include "rebraid/core/scene.h"

#include <cmath>

#include "rebraid/core/error.h"

namespace rebraid {

BBox3f Mesh::bounds() const {
    // Only positions that some triangle uses count: unused vertices must not inflate the box.
    BBox3f box;
    for (const Triangle& t : triangles)
        for (std::uint32_t index : t) box.extend(positions[index]);
    return box;
}

std::uint64_t Scene::instanced_triangle_count() const {
    std::uint64_t count = 0;
    for (const Instance& instance : instances) count += meshes[instance.mesh_id].triangles.size();
    return count;
}

std::uint64_t Scene::mesh_triangle_count() const {
    std::uint64_t count = 0;
    for (const Mesh& mesh : meshes) count += mesh.triangles.size();
    return count;
}

BBox3f Scene::instance_bounds(InstanceId id) const {
    const Instance& instance = instances[id];
    return instance.object_to_world.transform_bbox(meshes[instance.mesh_id].bounds());
}

BBox3f Scene::bounds() const {
    std::vector<BBox3f> mesh_bounds;
    mesh_bounds.reserve(meshes.size());
    for (const Mesh& mesh : meshes) mesh_bounds.push_back(mesh.bounds());
    BBox3f box;
    for (const Instance& instance : instances)
        box.extend(instance.object_to_world.transform_bbox(mesh_bounds[instance.mesh_id]));
    return box;
}

void Scene::validate(SingularTransforms singular) const {
    for (std::size_t m = 0; m < meshes.size(); ++m) {
        const Mesh& mesh = meshes[m];
        for (std::size_t v = 0; v < mesh.positions.size(); ++v)
            if (!is_finite(mesh.positions[v]))
                throw Error("scene: mesh " + std::to_string(m) + " ('" + mesh.name + "') vertex " +
                            std::to_string(v) + " is not finite");
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
            for (std::uint32_t index : mesh.triangles[t])
                if (index >= mesh.positions.size())
                    throw Error("scene: mesh " + std::to_string(m) + " ('" + mesh.name +
                                "') triangle " + std::to_string(t) + " uses vertex " +
                                std::to_string(index) + ", mesh has " +
                                std::to_string(mesh.positions.size()) + " vertices");
    }
    for (std::size_t i = 0; i < instances.size(); ++i) {
        const Instance& instance = instances[i];
        if (instance.mesh_id >= meshes.size())
            throw Error("scene: instance " + std::to_string(i) + " references mesh " +
                        std::to_string(instance.mesh_id) + ", scene has " +
                        std::to_string(meshes.size()) + " meshes");
        const AffineTransform& xfm = instance.object_to_world;
        if (!xfm.is_finite())
            throw Error("scene: instance " + std::to_string(i) + " has a non-finite transform");
        // Rays are mapped into object space with the inverse: a singular map has none.
        const float det = xfm.determinant();
        if (!std::isfinite(det) ||
            (singular == SingularTransforms::rejected && is_singular_transform(xfm)))
            throw Error("scene: instance " + std::to_string(i) +
                        " has a singular transform (determinant " + std::to_string(det) + ")");
    }
}

}  // namespace rebraid
