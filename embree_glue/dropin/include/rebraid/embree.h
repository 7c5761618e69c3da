#pragma once

// Re-braiding for Embree applications: `rebraid::EmbreeAccel accel(scene);` over a committed
// RTCScene, then `accel.intersect1(rayhit)` / `accel.occluded1(ray)` where the application
// called rtcIntersect1 / rtcOccluded1; or `rebraid::EmbreeUserGeometryScene rebraided(accel);`
// and trace `rebraided.get()` with the unchanged calls. Link rebraid::embree_dropin (it must
// come before libembree3 on the link line; the CMake target takes care of that). README,
// "Using rebraid from an Embree application", and docs/embree.md.

#include "embree_glue/dropin/embree_accel.h"
#include "embree_glue/dropin/embree_interposer_registry.h"
#include "embree_glue/dropin/embree_user_geometry.h"
