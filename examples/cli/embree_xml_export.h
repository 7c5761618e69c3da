#pragma once

#include <cstddef>
#include <string>

#include "rebraid/core/scene.h"

namespace rebraid::cli {

/// What write_embree_xml wrote.
struct EmbreeXmlExport {
    std::string scene_file;     ///< DIR/scene.xml
    std::string camera_file;    ///< DIR/camera.cfg: options for the tutorials' -c
    std::size_t meshes = 0;     ///< OBJ files written (meshes with triangles)
    std::size_t instances = 0;  ///< Transform nodes written
};

/// Writes `scene` for Embree's tutorial programs into the folder `dir` (created when missing):
///   scene.xml   Embree's tutorial XML: each mesh loaded once from its OBJ file and named
///               (<assign type="scene">), then one <Transform> per instance referring to it,
///               so that `viewer --instancing geometry` makes one Embree instance per instance
///               over shared meshes, and `--instancing none` bakes the transforms in;
///   mesh_N.obj  mesh N's positions and triangles (object space);
///   camera.cfg  --vp/--vi/--vu/--fov looking at the whole scene (pass it with -c).
/// Numbers are written with 9 significant digits, so they read back as the same floats.
/// Meshes without triangles and their instances are left out. Throws rebraid::Error naming the
/// file that cannot be written.
EmbreeXmlExport write_embree_xml(const Scene& scene, const std::string& dir);

}  // namespace rebraid::cli
