// `rebraid export SCENE --embree-xml DIR`: write a scene for Embree's own tutorial programs.
#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "embree_xml_export.h"
#include "scene_source.h"

namespace rebraid::cli {

namespace {

struct ExportOptions {
    std::string scene_path;
    std::string embree_xml_dir;
};

void run_export(const ExportOptions& options) {
    check_scene_file(options.scene_path);
    const Scene scene = load_scene(options.scene_path);
    const EmbreeXmlExport written = write_embree_xml(scene, options.embree_xml_dir);
    std::cout << "scene " << describe_scene(options.scene_path) << "\n"
              << "meshes " << written.meshes << "\n"
              << "instances " << written.instances << "\n"
              << "xml " << written.scene_file << "\n"
              << "camera " << written.camera_file << "\n";
}

}  // namespace

void add_export_command(CLI::App& app, CommonOptions& common, CommandAction& action) {
    auto options = std::make_shared<ExportOptions>();
    CLI::App* command = app.add_subcommand(
        "export",
        "Write a scene for Embree's tutorial programs (Debian's embree-tools): DIR/scene.xml, "
        "one mesh_N.obj per mesh, and DIR/camera.cfg, e.g. `viewer -i DIR/scene.xml -c "
        "DIR/camera.cfg --instancing geometry` (one Embree instance per instance over shared "
        "meshes) or `--instancing none` (transforms baked in).");
    command->add_option("SCENE", options->scene_path, "glTF scene (.gltf/.glb) or 'default'")
        ->required()
        ->type_name("SCENE");
    command
        ->add_option("--embree-xml", options->embree_xml_dir,
                     "folder to write the tutorial XML and OBJ files into")
        ->required()
        ->type_name("DIR");
    add_common_options(*command, common);
    command->callback([options, &action] { action = [options] { run_export(*options); }; });
}

}  // namespace rebraid::cli
