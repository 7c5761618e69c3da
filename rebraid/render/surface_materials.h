#pragma once

#include <array>
#include <string>
#include <vector>

#include "rebraid/core/scene.h"
#include "rebraid/io/gltf_material.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/render/surface_hit.h"
#include "rebraid/render/texture.h"

namespace rebraid::viewer {

/// The diffuse colour of every surface of a scene: the glTF material's base colour factor
/// times its base colour texture where the file has them; a soft per-instance tint
/// (instance_tint()) for surfaces without a material, and for every surface of a scene that
/// did not come from glTF.
class SurfaceMaterials {
public:
    /// Every surface gets its instance's tint.
    SurfaceMaterials() = default;

    /// Materials, textures and texture coordinates of a loaded glTF file (loaded with
    /// GltfLoadOptions::keep_model; `gltf_path` locates image files). Only images some
    /// material uses are decoded. A texture that cannot be read is left out with a message
    /// in `warnings` (its material keeps the factor). Throws rebraid::Error for malformed
    /// material data (see rebraid/io/gltf_material.h).
    static SurfaceMaterials from_gltf(const GltfLoadResult& loaded, const std::string& gltf_path,
                                      std::vector<std::string>& warnings);

    /// Linear base colour at `hit` on `scene` (the scene these materials were made for, or
    /// that scene posed by a GltfAnimator).
    Vec3f base_colour(const Scene& scene, const SurfaceHit& hit) const;

    std::size_t material_count() const { return materials_.size(); }
    std::size_t texture_count() const { return textures_.size(); }

private:
    struct Material {
        Vec3f factor{1.0f, 1.0f, 1.0f};  ///< linear RGB
        int texture = -1;                ///< index in textures_, -1 for none
        GltfSampler sampler;
    };
    struct TriangleRange {
        std::uint64_t first_triangle = 0;
        int material = -1;  ///< index in materials_, -1 for none
    };

    std::vector<Material> materials_;
    std::vector<Texture> textures_;
    /// Per MeshId, primitive ranges by first triangle (ascending).
    std::vector<std::vector<TriangleRange>> mesh_ranges_;
    /// Per MeshId, texture coordinates per vertex (empty: none).
    std::vector<std::vector<std::array<float, 2>>> mesh_uvs_;
    /// Per InstanceId, its glTF mesh: an animated scene may point instances at copies of
    /// their mesh (GltfAnimator), which have the same triangles but new MeshIds.
    std::vector<MeshId> instance_source_mesh_;
};

}  // namespace rebraid::viewer
