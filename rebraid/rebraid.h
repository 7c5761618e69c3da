#pragma once

// rebraid's public API: include this header and link rebraid::rebraid.
//
//   rebraid::Scene scene;                        // meshes + instances (core/scene.h)
//   auto accel = rebraid::build_rebraid_accel(scene);
//   rebraid::Hit hit = accel.intersect(ray);     // closest hit (core/accel.h)
//
// The headers below are what an application uses; everything else in the folders is the
// library's own machinery and is not installed.

// Scene model, rays and the structure interface.
#include "rebraid/core/accel.h"
#include "rebraid/core/animated_object.h"
#include "rebraid/core/bbox.h"
#include "rebraid/core/error.h"
#include "rebraid/core/ray.h"
#include "rebraid/core/scene.h"
#include "rebraid/core/transform.h"
#include "rebraid/core/triangle_test.h"
#include "rebraid/core/types.h"

// Object BVHs: the project's builder and its settings.
#include "rebraid/bvh/build_settings.h"
#include "rebraid/bvh/object_bvh_builder.h"

// The structures: flat (one BVH), plain two-level and re-braided; their SAH.
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/rebraiding/rebraid_settings.h"
#include "rebraid/top_level/bvh_stats.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/instanced_accel.h"

// Objects that move: in-place updates and dynamic-in-static scenes.
#include "rebraid/dynamic/dynamic_scene.h"
#include "rebraid/dynamic/dynamic_scene_accel.h"
#include "rebraid/dynamic/object_bvh_update.h"

// Files: glTF scenes and animations in, scenes out, the ray file; generated scenes, rays
// and the built-in animated object.
#include "rebraid/generators/default_scene.h"
#include "rebraid/generators/random_rays.h"
#include "rebraid/generators/scene_generators.h"
#include "rebraid/generators/twisting_object.h"
#include "rebraid/io/gltf_animation.h"
#include "rebraid/io/gltf_dynamic_object.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/io/gltf_writer.h"
#include "rebraid/io/ray_file.h"
