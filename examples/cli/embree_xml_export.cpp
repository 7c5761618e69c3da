#include "embree_xml_export.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "rebraid/core/error.h"

namespace rebraid::cli {
namespace {

/// A float that reads back as the same float (9 significant digits).
std::string exact(float value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.9g", double(value));
    return text;
}

std::ofstream open_for_writing(const std::filesystem::path& path) {
    std::ofstream out(path, std::ios::binary);
    if (!out) throw Error("cannot write '" + path.string() + "'");
    return out;
}

void check_written(std::ofstream& out, const std::filesystem::path& path) {
    out.close();
    if (!out) throw Error("writing '" + path.string() + "' failed");
}

void write_obj(const Mesh& mesh, const std::filesystem::path& path) {
    std::ofstream out = open_for_writing(path);
    std::string text;
    for (const Vec3f& p : mesh.positions)
        text += "v " + exact(p.x) + " " + exact(p.y) + " " + exact(p.z) + "\n";
    for (const Triangle& t : mesh.triangles)  // OBJ counts vertices from 1
        text += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " +
                std::to_string(t[2] + 1) + "\n";
    out << text;
    check_written(out, path);
}

/// The tutorial XML's AffineSpace: three rows of the 3x4 matrix, each with its translation.
std::string affine_space(const AffineTransform& m) {
    const Vec3f columns[4] = {m.col_x, m.col_y, m.col_z, m.translation};
    std::string text;
    for (int row = 0; row < 3; ++row) {
        text += "\n        ";
        for (int column = 0; column < 4; ++column) {
            const Vec3f& c = columns[column];
            text += exact(row == 0 ? c.x : row == 1 ? c.y : c.z) + (column < 3 ? " " : "");
        }
    }
    return text + "\n      ";
}

std::string mesh_id(MeshId m) {
    return "mesh_" + std::to_string(m);
}

/// Looks at the scene's centre from outside its bounds, above and to the side.
std::string camera_options(const Scene& scene) {
    const BBox3f bounds = scene.bounds();
    const Vec3f center = bounds.is_empty() ? Vec3f{0, 0, 0} : bounds.center();
    const Vec3f extent = bounds.is_empty() ? Vec3f{1, 1, 1} : bounds.extent();
    const float radius =
        0.5f * std::sqrt(extent.x * extent.x + extent.y * extent.y + extent.z * extent.z);
    const Vec3f from = center + Vec3f{0.55f, 0.35f, 0.76f} * (2.2f * std::max(radius, 1e-6f));
    return "--vp " + exact(from.x) + " " + exact(from.y) + " " + exact(from.z) + " --vi " +
           exact(center.x) + " " + exact(center.y) + " " + exact(center.z) +
           " --vu 0 1 0 --fov 50\n";
}

}  // namespace

EmbreeXmlExport write_embree_xml(const Scene& scene, const std::string& dir) {
    const std::filesystem::path folder(dir);
    std::error_code error;
    std::filesystem::create_directories(folder, error);
    if (error) throw Error("cannot create the folder '" + dir + "': " + error.message());

    EmbreeXmlExport result;
    std::string xml = "<?xml version=\"1.0\"?>\n<scene>\n";
    std::vector<bool> is_written(scene.meshes.size(), false);
    for (MeshId m = 0; m < scene.meshes.size(); ++m) {
        if (scene.meshes[m].triangles.empty()) continue;
        const std::string file = mesh_id(m) + ".obj";
        write_obj(scene.meshes[m], folder / file);
        xml += "  <assign type=\"scene\" id=\"" + mesh_id(m) + "\">\n    <obj src=\"" + file +
               "\"/>\n  </assign>\n";
        is_written[m] = true;
        ++result.meshes;
    }
    for (const Instance& instance : scene.instances) {
        if (!is_written[instance.mesh_id]) continue;
        xml += "  <Transform>\n    <AffineSpace>" + affine_space(instance.object_to_world) +
               "</AffineSpace>\n    <ref id=\"" + mesh_id(instance.mesh_id) +
               "\"/>\n  </Transform>\n";
        ++result.instances;
    }
    xml += "</scene>\n";

    const std::filesystem::path scene_file = folder / "scene.xml";
    std::ofstream out = open_for_writing(scene_file);
    out << xml;
    check_written(out, scene_file);
    const std::filesystem::path camera_file = folder / "camera.cfg";
    std::ofstream camera = open_for_writing(camera_file);
    camera << camera_options(scene);
    check_written(camera, camera_file);
    result.scene_file = scene_file.string();
    result.camera_file = camera_file.string();
    return result;
}

}  // namespace rebraid::cli
