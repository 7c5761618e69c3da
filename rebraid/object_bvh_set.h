#pragma once

#include <functional>
#include <vector>

#include "rebraid/build_settings.h"
#include "rebraid/object_bvh.h"
#include "rebraid/scene.h"

namespace rebraid {

/// How object BVHs are made: the project's builder (default) or, from embree_glue,
/// Embree's rtcBuildBVH. Must be callable from several threads at once.
using ObjectBvhBuilder = std::function<ObjectBvh(const Mesh&)>;

/// The project's binned-SAH builder with `settings`.
ObjectBvhBuilder own_object_bvh_builder(const BuildSettings& settings = {});

/// One ObjectBvh per mesh of `scene` (index = MeshId), built in parallel.
std::vector<ObjectBvh> build_object_bvhs(const Scene& scene, const ObjectBvhBuilder& builder);

}  // namespace rebraid
