#include "rebraid/io/gltf_writer.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <vector>

#include "rebraid/core/error.h"
#include "rebraid/io/gltf_gpu_instancing.h"
#include "rebraid/io/gltf_instance_pose.h"

namespace rebraid {
namespace {

/// A GLB stores its total length in 32 bits; keep the buffer well below, leaving room for
/// the JSON chunk.
constexpr std::uint64_t kMaxBufferBytes = std::numeric_limits<std::uint32_t>::max() / 2;

class GltfWriter {
public:
    GltfWriter(const Scene& scene, const std::string& path, const GltfWriteSettings& settings)
        : scene_(scene), path_(path), settings_(settings) {}

    void write() {
        const std::string extension = lower_case_extension();
        if (extension != ".glb" && extension != ".gltf")
            fail("unknown extension '" + extension + "' (expected .glb or .gltf)");
        check_scene();
        model_.asset.version = "2.0";
        model_.asset.generator = "rebraid write_gltf_scene";
        model_.buffers.resize(1);
        // Meshes without triangles are left out: only hidden instances use them.
        for (const Mesh& mesh : scene_.meshes) {
            gltf_mesh_ids_.push_back(mesh.triangles.empty() ? -1 : int(model_.meshes.size()));
            if (!mesh.triangles.empty()) add_mesh(mesh);
        }
        add_nodes();
        if (extension == ".glb")
            write_binary();
        else
            write_text();
    }

private:
    [[noreturn]] void fail(const std::string& what) const {
        throw Error("cannot write scene file '" + path_ + "': " + what);
    }

    std::string lower_case_extension() const {
        std::string extension = std::filesystem::path(path_).extension().string();
        std::transform(extension.begin(), extension.end(), extension.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        return extension;
    }

    void check_scene() const {
        try {
            // Singular transforms are written as hidden instances.
            scene_.validate(SingularTransforms::allowed);
        } catch (const Error& error) {
            fail(std::string("invalid scene: ") + error.what());
        }
        // The loader rejects a scene without instances, and a glTF mesh needs a primitive.
        if (scene_.instances.empty()) fail("the scene has no instances");
        std::vector<bool> is_used(scene_.meshes.size(), false);
        for (const Instance& instance : scene_.instances) is_used[instance.mesh_id] = true;
        std::uint64_t bytes = 0;
        bool has_triangles = false;
        for (std::size_t m = 0; m < scene_.meshes.size(); ++m) {
            const Mesh& mesh = scene_.meshes[m];
            // An empty mesh comes back only as the loader's mesh of hidden instances.
            if (mesh.triangles.empty() && !is_used[m])
                fail("mesh " + std::to_string(m) + " ('" + mesh.name +
                     "') has no triangles and no instance, which glTF cannot store");
            has_triangles = has_triangles || !mesh.triangles.empty();
            bytes += mesh.positions.size() * sizeof(Vec3f) + mesh.triangles.size() * 12 + 8;
        }
        if (!has_triangles)
            fail("no mesh has triangles: the nodes of hidden instances need a glTF mesh");
        if (bytes > kMaxBufferBytes)
            fail("the meshes need " + std::to_string(bytes) + " bytes, more than glTF's limit");
    }

    /// Appends `size` bytes to the buffer as a new bufferView (4-byte aligned); returns it.
    int add_view(const void* data, std::size_t size, int target) {
        std::vector<unsigned char>& bytes = model_.buffers[0].data;
        tinygltf::BufferView view;
        view.buffer = 0;
        view.byteOffset = bytes.size();
        view.byteLength = size;
        view.target = target;
        const auto* first = static_cast<const unsigned char*>(data);
        bytes.insert(bytes.end(), first, first + size);
        bytes.resize((bytes.size() + 3) / 4 * 4, 0);
        model_.bufferViews.push_back(view);
        return static_cast<int>(model_.bufferViews.size() - 1);
    }

    int add_accessor(int view, int component_type, std::size_t count, int type) {
        tinygltf::Accessor accessor;
        accessor.bufferView = view;
        accessor.componentType = component_type;
        accessor.count = count;
        accessor.type = type;
        model_.accessors.push_back(accessor);
        return static_cast<int>(model_.accessors.size() - 1);
    }

    int add_positions(const Mesh& mesh) {
        const int view = add_view(mesh.positions.data(), mesh.positions.size() * sizeof(Vec3f),
                                  TINYGLTF_TARGET_ARRAY_BUFFER);
        const int accessor = add_accessor(view, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                          mesh.positions.size(), TINYGLTF_TYPE_VEC3);
        // The glTF specification requires min and max on POSITION accessors.
        const BBox3f bounds = mesh.bounds();
        model_.accessors[accessor].minValues = {bounds.min.x, bounds.min.y, bounds.min.z};
        model_.accessors[accessor].maxValues = {bounds.max.x, bounds.max.y, bounds.max.z};
        return accessor;
    }

    /// Indices as unsigned short when every vertex fits (smaller files), else unsigned int.
    int add_indices(const Mesh& mesh) {
        const std::size_t count = mesh.triangles.size() * 3;
        if (mesh.positions.size() <= std::numeric_limits<std::uint16_t>::max()) {
            std::vector<std::uint16_t> indices;
            indices.reserve(count);
            for (const Triangle& t : mesh.triangles)
                for (std::uint32_t v : t) indices.push_back(static_cast<std::uint16_t>(v));
            const int view = add_view(indices.data(), count * sizeof(std::uint16_t),
                                      TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
            return add_accessor(view, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, count,
                                TINYGLTF_TYPE_SCALAR);
        }
        static_assert(sizeof(Triangle) == 3 * sizeof(std::uint32_t));
        const int view = add_view(mesh.triangles.data(), count * sizeof(std::uint32_t),
                                  TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
        return add_accessor(view, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, count,
                            TINYGLTF_TYPE_SCALAR);
    }

    void add_mesh(const Mesh& mesh) {
        tinygltf::Primitive primitive;
        primitive.attributes["POSITION"] = add_positions(mesh);
        primitive.indices = add_indices(mesh);
        primitive.mode = TINYGLTF_MODE_TRIANGLES;
        tinygltf::Mesh gltf_mesh;
        gltf_mesh.name = mesh.name;
        gltf_mesh.primitives.push_back(primitive);
        model_.meshes.push_back(gltf_mesh);
    }

    /// Hidden: an instance of a mesh without triangles or with a singular transform. It is
    /// never hit, so it is written as the loader reads a hidden instance back: a zero scale.
    bool is_hidden(const Instance& instance) const {
        return gltf_mesh_ids_[instance.mesh_id] < 0 ||
               is_singular_transform(instance.object_to_world);
    }

    /// The glTF mesh a node of `instance` references: its own, or for an instance of a mesh
    /// without triangles the first glTF mesh (a hidden node draws none, but needs one).
    int gltf_mesh_of(const Instance& instance) const {
        return std::max(gltf_mesh_ids_[instance.mesh_id], 0);
    }

    /// A node with a zero scale, hiding `instance`.
    int add_hidden_node(const Instance& instance) {
        tinygltf::Node node;
        node.mesh = gltf_mesh_of(instance);
        node.scale = {0.0, 0.0, 0.0};
        model_.nodes.push_back(std::move(node));
        return static_cast<int>(model_.nodes.size() - 1);
    }

    int add_matrix_node(const Instance& instance) {
        const AffineTransform& t = instance.object_to_world;
        tinygltf::Node node;
        node.mesh = gltf_mesh_of(instance);
        // Column-major 4x4 with bottom row (0 0 0 1); floats widen to double exactly.
        node.matrix = {t.col_x.x,       t.col_x.y,       t.col_x.z,       0.0,
                       t.col_y.x,       t.col_y.y,       t.col_y.z,       0.0,
                       t.col_z.x,       t.col_z.y,       t.col_z.z,       0.0,
                       t.translation.x, t.translation.y, t.translation.z, 1.0};
        model_.nodes.push_back(std::move(node));
        return static_cast<int>(model_.nodes.size() - 1);
    }

    /// One EXT_mesh_gpu_instancing node for `poses` (instances of glTF mesh `mesh`, in
    /// order).
    int add_instanced_node(int mesh, const std::vector<GltfInstancePose>& poses) {
        std::vector<float> translations, rotations, scales;
        for (const GltfInstancePose& pose : poses) {
            translations.insert(translations.end(), pose.translation.begin(),
                                pose.translation.end());
            rotations.insert(rotations.end(), pose.rotation.begin(), pose.rotation.end());
            scales.insert(scales.end(), pose.scale.begin(), pose.scale.end());
        }
        auto add_attribute = [&](const std::vector<float>& values, int type) {
            const int view = add_view(values.data(), values.size() * sizeof(float), 0);
            return tinygltf::Value(
                add_accessor(view, TINYGLTF_COMPONENT_TYPE_FLOAT, poses.size(), type));
        };
        tinygltf::Value::Object attributes;
        attributes["TRANSLATION"] = add_attribute(translations, TINYGLTF_TYPE_VEC3);
        attributes["ROTATION"] = add_attribute(rotations, TINYGLTF_TYPE_VEC4);
        attributes["SCALE"] = add_attribute(scales, TINYGLTF_TYPE_VEC3);
        tinygltf::Value::Object extension;
        extension["attributes"] = tinygltf::Value(std::move(attributes));
        tinygltf::Node node;
        node.mesh = mesh;
        node.extensions[kGltfGpuInstancing] = tinygltf::Value(std::move(extension));
        model_.nodes.push_back(std::move(node));
        return static_cast<int>(model_.nodes.size() - 1);
    }

    void add_nodes() {
        tinygltf::Scene gltf_scene;
        const std::vector<Instance>& instances = scene_.instances;
        // A hidden element: a zero scale.
        const GltfInstancePose hidden_pose{.scale = {0.0f, 0.0f, 0.0f}};
        std::size_t i = 0;
        while (i < instances.size()) {
            // The longest run from i of one mesh with T * R * S transforms; hidden instances
            // join any run.
            std::vector<GltfInstancePose> poses;
            int run_mesh = -1;  // the glTF mesh of the run's shown instances, -1 before one
            if (settings_.gpu_instancing) {
                for (std::size_t end = i; end < instances.size(); ++end) {
                    const Instance& instance = instances[end];
                    if (is_hidden(instance)) {
                        poses.push_back(hidden_pose);
                        continue;
                    }
                    if (run_mesh >= 0 && gltf_mesh_of(instance) != run_mesh) break;
                    const std::optional<GltfInstancePose> pose =
                        decompose_instance_transform(instance.object_to_world);
                    if (!pose) break;
                    run_mesh = gltf_mesh_of(instance);
                    poses.push_back(*pose);
                }
            }
            if (poses.size() >= 2) {
                const int mesh = run_mesh >= 0 ? run_mesh : gltf_mesh_of(instances[i]);
                gltf_scene.nodes.push_back(add_instanced_node(mesh, poses));
                i += poses.size();
            } else {
                const Instance& instance = instances[i];
                gltf_scene.nodes.push_back(is_hidden(instance) ? add_hidden_node(instance)
                                                               : add_matrix_node(instance));
                ++i;
            }
        }
        if (model_.nodes.size() < instances.size()) {
            model_.extensionsUsed.push_back(kGltfGpuInstancing);
            // Required: a reader without it would show one instance per node, a wrong scene.
            model_.extensionsRequired.push_back(kGltfGpuInstancing);
        }
        model_.scenes.push_back(std::move(gltf_scene));
        model_.defaultScene = 0;
    }

    void write_binary() const {
        std::ofstream out(path_, std::ios::binary | std::ios::trunc);
        if (!out) fail("cannot create the file");
        tinygltf::TinyGLTF serializer;
        if (!serializer.WriteGltfSceneToStream(&model_, out, false, true))
            fail("tinygltf could not serialize the scene");
        out.close();
        if (!out) fail("cannot write the file");
    }

    void write_text() const {
        // tinygltf writes the buffer to "<stem>.bin" beside the .gltf and references it by
        // that relative URI; it reports files it cannot open, so check the size it wrote.
        tinygltf::TinyGLTF serializer;
        if (!serializer.WriteGltfSceneToFile(&model_, path_, false, false, true, false))
            fail("tinygltf could not write the file or its .bin buffer");
        const std::filesystem::path bin_path =
            std::filesystem::path(path_).replace_extension(".bin");
        std::error_code error;
        const std::uintmax_t bin_size = std::filesystem::file_size(bin_path, error);
        if (error || bin_size != model_.buffers[0].data.size())
            fail("the buffer file '" + bin_path.string() + "' was not written completely");
        if (std::filesystem::file_size(path_, error) == 0 || error) fail("cannot write the file");
    }

    const Scene& scene_;
    std::string path_;
    GltfWriteSettings settings_;
    tinygltf::Model model_;
    std::vector<int> gltf_mesh_ids_;  ///< per Mesh, its glTF mesh; -1 for one without triangles
};

}  // namespace

void write_gltf_scene(const Scene& scene, const std::string& path,
                      const GltfWriteSettings& settings) {
    GltfWriter(scene, path, settings).write();
}

}  // namespace rebraid
