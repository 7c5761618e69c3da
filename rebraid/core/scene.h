#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "rebraid/core/bbox.h"
#include "rebraid/core/transform.h"
#include "rebraid/core/types.h"

namespace rebraid {

/// Vertex indices of one triangle into Mesh::positions.
using Triangle = std::array<std::uint32_t, 3>;

/// One object: triangles in object space. A triangle's PrimId is its index in `triangles`.
struct Mesh {
    std::string name;
    std::vector<Vec3f> positions;
    std::vector<Triangle> triangles;

    BBox3f bounds() const;
    /// Positions of triangle `prim_id`'s three corners.
    std::array<Vec3f, 3> corners(PrimId prim_id) const {
        const Triangle& t = triangles[prim_id];
        return {positions[t[0]], positions[t[1]], positions[t[2]]};
    }
};

/// Instance transforms whose |determinant| is below this are singular: they have no inverse
/// to map rays into object space with. Scene::validate() rejects them; the glTF loader and
/// animator hide such an instance instead (README "Conventions", hidden instances).
inline constexpr float kMinInstanceDeterminant = 1e-30f;

/// True when `transform` is singular: |determinant| below kMinInstanceDeterminant (or not a
/// number). Check AffineTransform::is_finite() first where a non-finite map is an error.
inline bool is_singular_transform(const AffineTransform& transform) {
    return !(std::fabs(transform.determinant()) >= kMinInstanceDeterminant);
}

/// One placement of a mesh in the world. Several instances may share a mesh.
struct Instance {
    MeshId mesh_id = 0;
    AffineTransform object_to_world;
};

/// Whether Scene::validate() accepts singular instance transforms.
enum class SingularTransforms {
    rejected,  ///< an error: every structure maps rays with the inverse transform
    allowed,   ///< accepted (write_gltf_scene() writes such an instance hidden)
};

/// Meshes and their instances: the input of every structure in the project.
struct Scene {
    std::vector<Mesh> meshes;
    std::vector<Instance> instances;

    /// Triangles over all instances (a mesh counts once per instance).
    std::uint64_t instanced_triangle_count() const;
    /// Triangles over the distinct meshes.
    std::uint64_t mesh_triangle_count() const;
    /// World-space bounds of instance `id` (its mesh's box transformed, conservatively).
    BBox3f instance_bounds(InstanceId id) const;
    /// World-space bounds of the whole scene.
    BBox3f bounds() const;

    /// Throws rebraid::Error naming the first problem: an instance referencing a missing
    /// mesh, a non-finite or (unless `singular` allows it) singular transform, a triangle
    /// index past its mesh's positions, a non-finite vertex position. Degenerate triangles
    /// are legal (they never produce hits).
    void validate(SingularTransforms singular = SingularTransforms::rejected) const;
};

}  // namespace rebraid
