#include "rebraid/object_bvh_set.h"

#include <tbb/parallel_for.h>

namespace rebraid {

ObjectBvhBuilder own_object_bvh_builder(const BuildSettings& settings) {
    settings.validate();
    return [settings](const Mesh& mesh) { return build_object_bvh(mesh, settings); };
}

std::vector<ObjectBvh> build_object_bvhs(const Scene& scene, const ObjectBvhBuilder& builder) {
    std::vector<ObjectBvh> bvhs(scene.meshes.size());
    // One task per mesh; each build parallelises internally when its mesh is large.
    tbb::parallel_for(std::size_t(0), scene.meshes.size(), std::size_t(1),
                      [&](std::size_t m) { bvhs[m] = builder(scene.meshes[m]); });
    return bvhs;
}

}  // namespace rebraid
