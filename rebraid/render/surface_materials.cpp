#include "rebraid/render/surface_materials.h"

#include <algorithm>
#include <map>

#include "rebraid/core/error.h"
#include "rebraid/render/shading.h"

namespace rebraid::viewer {

SurfaceMaterials SurfaceMaterials::from_gltf(const GltfLoadResult& loaded,
                                             const std::string& gltf_path,
                                             std::vector<std::string>& warnings) {
    SurfaceMaterials result;
    const std::vector<GltfMaterial> materials = read_gltf_materials(loaded);
    const std::vector<GltfImageSource> images = read_gltf_image_sources(loaded, gltf_path);

    // Decode each used image once, however many materials share it.
    std::map<std::uint32_t, int> texture_of_image;
    for (std::size_t m = 0; m < materials.size(); ++m) {
        const GltfMaterial& source = materials[m];
        Material material;
        material.factor = {source.base_colour_factor[0], source.base_colour_factor[1],
                           source.base_colour_factor[2]};
        if (source.base_colour_texture) {
            const std::uint32_t image_id = source.base_colour_texture->image_id;
            material.sampler = source.base_colour_texture->sampler;
            auto found = texture_of_image.find(image_id);
            if (found == texture_of_image.end()) {
                int texture_id = -1;
                const std::string label =
                    "image " + std::to_string(image_id) + " ('" + images[image_id].name + "')";
                try {
                    result.textures_.push_back(Texture::decode(images[image_id], label));
                    texture_id = static_cast<int>(result.textures_.size()) - 1;
                } catch (const Error& error) {
                    warnings.push_back(std::string(error.what()) + "; material " +
                                       std::to_string(m) + " uses its colour factor only");
                }
                found = texture_of_image.emplace(image_id, texture_id).first;
            }
            material.texture = found->second;
        }
        result.materials_.push_back(material);
    }

    result.mesh_uvs_ = read_gltf_base_colour_uvs(loaded, materials);
    for (const Instance& instance : loaded.scene.instances)
        result.instance_source_mesh_.push_back(instance.mesh_id);
    result.mesh_ranges_.resize(loaded.scene.meshes.size());
    for (std::size_t mesh = 0; mesh < loaded.report.mesh_primitives.size(); ++mesh)
        for (const GltfPrimitiveRange& range : loaded.report.mesh_primitives[mesh]) {
            const bool has_material =
                range.material >= 0 && static_cast<std::size_t>(range.material) < materials.size();
            result.mesh_ranges_[mesh].push_back(
                {range.first_triangle, has_material ? range.material : -1});
        }
    return result;
}

Vec3f SurfaceMaterials::base_colour(const Scene& scene, const SurfaceHit& hit) const {
    const MeshId scene_mesh_id = scene.instances[hit.instance_id].mesh_id;
    const MeshId mesh_id = hit.instance_id < instance_source_mesh_.size()
                               ? instance_source_mesh_[hit.instance_id]
                               : scene_mesh_id;
    if (mesh_id >= mesh_ranges_.size() || mesh_ranges_[mesh_id].empty())
        return instance_tint(hit.instance_id);
    // The last range starting at or before the triangle holds it.
    const std::vector<TriangleRange>& ranges = mesh_ranges_[mesh_id];
    const auto after = std::ranges::upper_bound(ranges, std::uint64_t{hit.prim_id}, {},
                                                &TriangleRange::first_triangle);
    if (after == ranges.begin()) return instance_tint(hit.instance_id);
    const int material_id = std::prev(after)->material;
    if (material_id < 0) return instance_tint(hit.instance_id);

    const Material& material = materials_[static_cast<std::size_t>(material_id)];
    if (material.texture < 0) return material.factor;
    float s = 0.0f, t = 0.0f;
    const auto& uvs = mesh_uvs_[mesh_id];
    if (!uvs.empty()) {
        const Triangle& triangle = scene.meshes[scene_mesh_id].triangles[hit.prim_id];
        const float w0 = 1.0f - hit.u - hit.v;
        s = uvs[triangle[0]][0] * w0 + uvs[triangle[1]][0] * hit.u + uvs[triangle[2]][0] * hit.v;
        t = uvs[triangle[0]][1] * w0 + uvs[triangle[1]][1] * hit.u + uvs[triangle[2]][1] * hit.v;
    }
    return material.factor *
           textures_[static_cast<std::size_t>(material.texture)].sample(s, t, material.sampler);
}

}  // namespace rebraid::viewer
