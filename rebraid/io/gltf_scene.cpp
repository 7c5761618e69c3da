#include "rebraid/io/gltf_scene.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "rebraid/core/error.h"
#include "rebraid/io/gltf_accessor.h"
#include "rebraid/io/gltf_animation_math.h"
#include "rebraid/io/gltf_draco.h"
#include "rebraid/io/gltf_gpu_instancing.h"
#include "rebraid/io/gltf_meshopt.h"
#include "rebraid/io/gltf_tinygltf_fixups.h"

namespace rebraid {
namespace {

// Mesh::Triangle holds 32-bit vertex indices, so no mesh may have more positions than this.
constexpr std::uint64_t kMaxMeshPositions = std::numeric_limits<std::uint32_t>::max();

// Node chains are composed in double, so long chains do not drift, and converted to
// AffineTransform once per instance.
using gltf_animation::Affine3d;

/// Number text for messages (std::to_string prints 1e-40 as 0.000000).
std::string format_number(double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.9g", value);
    return text;
}

bool skip_image_decoding(tinygltf::Image*, const int, std::string*, std::string*, int, int,
                         const unsigned char*, int, void*) {
    return true;  // geometry only: images are never decoded
}

/// Deepest nesting of JSON arrays and objects the loader accepts. tinygltf converts `extras`
/// and `extensions` recursively, so a hostile file nested 100,000 levels deep overflowed the
/// stack (tests/cli/bad_input_test.cpp); real glTF files nest about ten levels.
constexpr std::size_t kMaxJsonNesting = 512;

/// Deepest nesting of arrays and objects in JSON `text` (brackets inside strings do not
/// count); stops counting past `limit`.
std::size_t json_nesting_depth(const unsigned char* text, std::size_t size, std::size_t limit) {
    std::size_t depth = 0, deepest = 0;
    bool in_string = false;
    for (std::size_t i = 0; i < size && deepest <= limit; ++i) {
        const unsigned char c = text[i];
        if (in_string) {
            if (c == '\\')
                ++i;  // the escaped character cannot end the string
            else if (c == '"')
                in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if (c == '[' || c == '{') {
            deepest = std::max(deepest, ++depth);
        } else if ((c == ']' || c == '}') && depth > 0) {
            --depth;
        }
    }
    return deepest;
}

std::uint32_t read_u32_le(const std::vector<unsigned char>& bytes, std::size_t at) {
    return std::uint32_t(bytes[at]) | std::uint32_t(bytes[at + 1]) << 8 |
           std::uint32_t(bytes[at + 2]) << 16 | std::uint32_t(bytes[at + 3]) << 24;
}

class GltfLoader {
public:
    GltfLoader(const std::string& path, const GltfLoadOptions& options)
        : path_(path), options_(options) {}

    GltfLoadResult load() {
        parse_model(read_file());
        decode_gltf_meshopt_views(model_, error_prefix());
        for (std::size_t m = 0; m < model_.meshes.size(); ++m) load_mesh(m);
        add_scene_instances();
        try {
            result_.scene.validate();
        } catch (const Error& error) {
            fail(error.what());
        }
        if (options_.keep_model)
            result_.model = std::make_shared<const tinygltf::Model>(std::move(model_));
        return std::move(result_);
    }

private:
    std::string error_prefix() const { return "scene file '" + path_ + "': "; }
    [[noreturn]] void fail(const std::string& what) const { throw Error(error_prefix() + what); }

    std::string mesh_label(std::size_t m) const {
        return "mesh " + std::to_string(m) + " ('" + model_.meshes[m].name + "')";
    }
    std::string node_label(std::size_t n) const {
        return "node " + std::to_string(n) + " ('" + model_.nodes[n].name + "')";
    }

    // ---- File and container ---------------------------------------------------------------

    std::vector<unsigned char> read_file() const {
        std::error_code ec;
        if (!std::filesystem::exists(path_, ec)) fail("cannot open file: no such file");
        if (!std::filesystem::is_regular_file(path_, ec))
            fail("cannot open file: not a regular file");
        const std::uintmax_t size = std::filesystem::file_size(path_, ec);
        if (ec) fail("cannot read file: " + ec.message());
        if (size == 0) fail("malformed glTF: the file is empty");
        // tinygltf takes the length as a 32-bit unsigned int.
        if (size >= std::numeric_limits<unsigned int>::max())
            fail("file too large (" + std::to_string(size) + " bytes, limit 4 GiB)");
        std::vector<unsigned char> bytes(size);
        std::ifstream in(path_, std::ios::binary);
        if (!in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size)))
            fail("cannot read file");
        return bytes;
    }

    /// GLB chunk layout checked before tinygltf sees it: tinygltf 2.7 trusts the BIN chunk
    /// length up to 8 bytes past the end of the file.
    void check_glb_layout(const std::vector<unsigned char>& bytes) const {
        const std::uint64_t size = bytes.size();
        if (size < 20)
            fail("malformed glTF: truncated GLB (" + std::to_string(size) +
                 " bytes, the header alone needs 20)");
        if (std::memcmp(bytes.data(), "glTF", 4) != 0)
            fail("malformed glTF: not a binary glTF file (bad magic)");
        const std::uint64_t declared_length = read_u32_le(bytes, 8);
        const std::uint64_t json_end = 20 + std::uint64_t(read_u32_le(bytes, 12));
        if (declared_length > size)
            fail("malformed glTF: truncated GLB (header declares " +
                 std::to_string(declared_length) + " bytes, file has " + std::to_string(size) +
                 ")");
        if (json_end > declared_length)
            fail("malformed glTF: truncated GLB (JSON chunk ends at byte " +
                 std::to_string(json_end) + ", file has " + std::to_string(declared_length) + ")");
        if (json_end == declared_length) return;  // no BIN chunk
        if (json_end + 8 > declared_length)
            fail("malformed glTF: truncated GLB (incomplete BIN chunk header)");
        const std::uint64_t bin_end = json_end + 8 + read_u32_le(bytes, json_end);
        if (bin_end > declared_length)
            fail("malformed glTF: truncated GLB (BIN chunk ends at byte " +
                 std::to_string(bin_end) + ", file has " + std::to_string(declared_length) + ")");
    }

    void parse_model(std::vector<unsigned char> bytes) {
        tinygltf::TinyGLTF parser;
        parser.SetImageLoader(&skip_image_decoding, nullptr);
        const std::string base_dir = std::filesystem::path(path_).parent_path().string();
        const bool is_binary = (bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0) ||
                               std::filesystem::path(path_).extension() == ".glb";
        std::string error, warning;
        bool ok = false;
        if (is_binary) check_glb_layout(bytes);
        const std::size_t json_offset = is_binary ? 20 : 0;
        const std::size_t json_size = is_binary ? read_u32_le(bytes, 12) : bytes.size();
        if (json_nesting_depth(bytes.data() + json_offset, json_size, kMaxJsonNesting) >
            kMaxJsonNesting)
            fail("malformed glTF: JSON nested deeper than " + std::to_string(kMaxJsonNesting) +
                 " levels");
        const GltfJsonFixes fixes = fix_gltf_json_for_tinygltf(bytes, is_binary);
        if (is_binary) {
            ok = parser.LoadBinaryFromMemory(&model_, &error, &warning, bytes.data(),
                                             static_cast<unsigned int>(bytes.size()), base_dir);
        } else {
            ok = parser.LoadASCIIFromString(&model_, &error, &warning,
                                            reinterpret_cast<const char*>(bytes.data()),
                                            static_cast<unsigned int>(bytes.size()), base_dir);
        }
        while (!error.empty() && (error.back() == '\n' || error.back() == ' ')) error.pop_back();
        if (!ok)
            fail("malformed glTF: " + (error.empty() ? std::string("tinygltf failed") : error));
        undo_gltf_json_fixes(fixes, model_);
    }

    // ---- Accessors ---------------------------------------------------------------------------

    GltfElementRange resolve_accessor(int id, const std::string& role) const {
        return resolve_gltf_accessor(model_, id, role, error_prefix());
    }

    // ---- Meshes ------------------------------------------------------------------------------

    /// Appends the primitive's positions to `mesh`; returns how many were appended.
    std::uint64_t append_positions(const tinygltf::Primitive& primitive, const std::string& where,
                                   Mesh& mesh) {
        const auto position = primitive.attributes.find("POSITION");
        if (position == primitive.attributes.end()) fail(where + " has no POSITION attribute");
        const std::string role = "POSITION of " + where;
        const GltfElementRange range = resolve_accessor(position->second, role);
        const tinygltf::Accessor& accessor = model_.accessors[std::size_t(position->second)];
        // KHR_mesh_quantization adds (normalized or not) byte and short positions.
        const int component = accessor.componentType;
        if (accessor.type != TINYGLTF_TYPE_VEC3 ||
            (component != TINYGLTF_COMPONENT_TYPE_FLOAT &&
             component != TINYGLTF_COMPONENT_TYPE_BYTE &&
             component != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
             component != TINYGLTF_COMPONENT_TYPE_SHORT &&
             component != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT))
            fail(role + " must be a float, byte or short VEC3 accessor");
        if (range.count > options_.max_vertices - vertex_total_)
            fail("more than max_vertices = " + std::to_string(options_.max_vertices) +
                 " vertices (" + role + " adds " + std::to_string(range.count) + ")");
        if (mesh.positions.size() + range.count > kMaxMeshPositions)
            fail(where + ": the mesh has more than 2^32-1 vertices");
        vertex_total_ += range.count;
        const std::size_t base = mesh.positions.size();
        mesh.positions.resize(base + range.count);
        for (std::uint64_t v = 0; v < range.count; ++v) {
            const unsigned char* element = range.first + v * range.stride;
            Vec3f p;
            if (component == TINYGLTF_COMPONENT_TYPE_FLOAT) {
                std::memcpy(&p, element, sizeof p);
            } else {
                auto read = [&](int k) {
                    return float(read_gltf_component(element, component, accessor.normalized, k));
                };
                p = {read(0), read(1), read(2)};
            }
            if (!is_finite(p))
                fail(where + ": vertex " + std::to_string(v) + " position is not finite (" +
                     format_number(p.x) + ", " + format_number(p.y) + ", " + format_number(p.z) +
                     ")");
            mesh.positions[base + v] = p;
        }
        return range.count;
    }

    /// Vertex index i of a primitive: read from its index accessor, or i itself when there
    /// is none (non-indexed geometry).
    struct IndexSource {
        GltfElementRange range;
        int component_type = 0;  // 0 = implicit 0..count-1
        std::uint32_t at(std::uint64_t i) const {
            const unsigned char* p = range.first + i * range.stride;
            switch (component_type) {
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
                    return *p;
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                    std::uint16_t v;
                    std::memcpy(&v, p, sizeof v);
                    return v;
                }
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
                    std::uint32_t v;
                    std::memcpy(&v, p, sizeof v);
                    return v;
                }
                default:
                    return static_cast<std::uint32_t>(i);
            }
        }
    };

    IndexSource index_source(const tinygltf::Primitive& primitive, const std::string& where,
                             std::uint64_t vertex_count) const {
        IndexSource source;
        if (primitive.indices < 0) {
            source.range.count = vertex_count;
            return source;
        }
        const std::string role = "indices of " + where;
        source.range = resolve_accessor(primitive.indices, role);
        const tinygltf::Accessor& accessor = model_.accessors[std::size_t(primitive.indices)];
        source.component_type = accessor.componentType;
        if (accessor.type != TINYGLTF_TYPE_SCALAR ||
            (source.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
             source.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
             source.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
            fail(role + " must be an unsigned byte, short or int SCALAR accessor");
        return source;
    }

    /// Corners of triangle `t` of a primitive, in the glTF 2.0 specification's vertex order
    /// (section "Meshes", topology types).
    static std::array<std::uint64_t, 3> triangle_corners(int mode, std::uint64_t t) {
        if (mode == TINYGLTF_MODE_TRIANGLE_STRIP)
            return {t, t + 1 + t % 2, t + 2 - t % 2};  // p_i = {v_i, v_i+(1+i%2), v_i+(2-i%2)}
        if (mode == TINYGLTF_MODE_TRIANGLE_FAN) return {t + 1, t + 2, 0};
        return {3 * t, 3 * t + 1, 3 * t + 2};
    }

    void load_primitive(std::size_t m, std::size_t p, Mesh& mesh) {
        const tinygltf::Primitive& primitive = model_.meshes[m].primitives[p];
        const int mode = primitive.mode < 0 ? TINYGLTF_MODE_TRIANGLES : primitive.mode;
        const std::string where = mesh_label(m) + " primitive " + std::to_string(p);
        if (mode > TINYGLTF_MODE_TRIANGLE_FAN)
            fail(where + " has an invalid mode " + std::to_string(mode));
        ++result_.report.primitive_count_by_mode[std::size_t(mode)];
        if (mode < TINYGLTF_MODE_TRIANGLES) return;  // points and lines are skipped
        if (!primitive.targets.empty()) ++result_.report.morphed_primitive_count;

        const std::uint64_t base = mesh.positions.size();
        const std::uint64_t first_triangle = mesh.triangles.size();
        if (uses_gltf_draco(primitive)) {
            append_draco_primitive(primitive, where, mesh);
            result_.report.mesh_primitives[m].push_back(
                {std::uint32_t(p), base, mesh.positions.size() - base, first_triangle,
                 mesh.triangles.size() - first_triangle, primitive.material});
            return;
        }
        const std::uint64_t vertex_count = append_positions(primitive, where, mesh);
        const IndexSource indices = index_source(primitive, where, vertex_count);
        const std::uint64_t n = indices.range.count;
        if (mode == TINYGLTF_MODE_TRIANGLES && n % 3 != 0)
            fail(where + ": TRIANGLES needs a multiple of 3 vertex indices, got " +
                 std::to_string(n));
        if (mode != TINYGLTF_MODE_TRIANGLES && n < 3)
            fail(where + ": a triangle strip or fan needs 3 or more vertex indices, got " +
                 std::to_string(n));
        const std::uint64_t triangle_count = mode == TINYGLTF_MODE_TRIANGLES ? n / 3 : n - 2;
        if (triangle_count > options_.max_triangles - triangle_total_)
            fail("more than max_triangles = " + std::to_string(options_.max_triangles) +
                 " triangles (" + where + " adds " + std::to_string(triangle_count) + ")");
        triangle_total_ += triangle_count;

        mesh.triangles.reserve(mesh.triangles.size() + triangle_count);
        for (std::uint64_t t = 0; t < triangle_count; ++t) {
            Triangle triangle;
            const std::array<std::uint64_t, 3> corners = triangle_corners(mode, t);
            for (int c = 0; c < 3; ++c) {
                const std::uint32_t vertex = indices.at(corners[c]);
                if (vertex >= vertex_count)
                    fail("triangle " + std::to_string(mesh.triangles.size()) + " of " + where +
                         " uses vertex " + std::to_string(vertex) + ", the primitive has " +
                         std::to_string(vertex_count) + " vertices");
                triangle[c] = static_cast<std::uint32_t>(base + vertex);
            }
            mesh.triangles.push_back(triangle);
        }
        result_.report.mesh_primitives[m].push_back({std::uint32_t(p), base, vertex_count,
                                                     first_triangle, triangle_count,
                                                     primitive.material});
    }

    /// A KHR_draco_mesh_compression primitive: decoded points, then faces in decoded order.
    void append_draco_primitive(const tinygltf::Primitive& primitive, const std::string& where,
                                Mesh& mesh) {
        GltfDracoGeometry geometry = decode_gltf_draco_primitive(
            model_, primitive, where, error_prefix(), options_.max_vertices - vertex_total_,
            options_.max_triangles - triangle_total_);
        if (mesh.positions.size() + geometry.positions.size() > kMaxMeshPositions)
            fail(where + ": the mesh has more than 2^32-1 vertices");
        vertex_total_ += geometry.positions.size();
        triangle_total_ += geometry.triangles.size();
        const auto base = static_cast<std::uint32_t>(mesh.positions.size());
        mesh.positions.insert(mesh.positions.end(), geometry.positions.begin(),
                              geometry.positions.end());
        for (Triangle& triangle : geometry.triangles)
            for (std::uint32_t& vertex : triangle) vertex += base;
        mesh.triangles.insert(mesh.triangles.end(), geometry.triangles.begin(),
                              geometry.triangles.end());
    }

    void load_mesh(std::size_t m) {
        Mesh mesh;
        mesh.name = model_.meshes[m].name;
        result_.report.mesh_primitives.emplace_back();
        for (std::size_t p = 0; p < model_.meshes[m].primitives.size(); ++p)
            load_primitive(m, p, mesh);
        result_.scene.meshes.push_back(std::move(mesh));
    }

    // ---- Nodes -------------------------------------------------------------------------------

    Affine3d local_transform(std::size_t n) const {
        const tinygltf::Node& node = model_.nodes[n];
        auto check_size = [&](const std::vector<double>& values, std::size_t expected,
                              const char* what) {
            if (!values.empty() && values.size() != expected)
                fail(node_label(n) + " has a " + what + " of " + std::to_string(values.size()) +
                     " numbers, expected " + std::to_string(expected));
            for (double value : values)
                if (!std::isfinite(value))
                    fail(node_label(n) + " has a non-finite " + what + " value");
        };
        check_size(node.matrix, 16, "matrix");
        check_size(node.translation, 3, "translation");
        check_size(node.rotation, 4, "rotation");
        check_size(node.scale, 3, "scale");

        Affine3d local;
        if (!node.matrix.empty()) {
            const std::vector<double>& m = node.matrix;  // column-major 4x4
            // glTF requires matrices decomposable to TRS: the bottom row must be (0 0 0 1).
            constexpr double kTolerance = 1e-6;
            if (std::fabs(m[3]) > kTolerance || std::fabs(m[7]) > kTolerance ||
                std::fabs(m[11]) > kTolerance || std::fabs(m[15] - 1) > kTolerance)
                fail(node_label(n) + " has a matrix whose bottom row is not (0, 0, 0, 1)");
            for (int c = 0; c < 4; ++c) local.columns[c] = {m[4 * c], m[4 * c + 1], m[4 * c + 2]};
            return local;
        }
        // T * R * S: columns of the rotation scaled by S, then the translation.
        double x = 0, y = 0, z = 0, w = 1;
        if (!node.rotation.empty()) {
            const double length = std::sqrt(
                node.rotation[0] * node.rotation[0] + node.rotation[1] * node.rotation[1] +
                node.rotation[2] * node.rotation[2] + node.rotation[3] * node.rotation[3]);
            if (!(length > 0)) fail(node_label(n) + " has a zero rotation quaternion");
            x = node.rotation[0] / length, y = node.rotation[1] / length;
            z = node.rotation[2] / length, w = node.rotation[3] / length;
        }
        const std::array<double, 3> scale =
            node.scale.empty() ? std::array<double, 3>{1, 1, 1}
                               : std::array<double, 3>{node.scale[0], node.scale[1], node.scale[2]};
        const std::array<std::array<double, 3>, 3> rotation{{
            {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)},
            {2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w)},
            {2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)},
        }};
        for (int c = 0; c < 3; ++c)
            for (int row = 0; row < 3; ++row) local.columns[c][row] = rotation[c][row] * scale[c];
        if (!node.translation.empty())
            local.columns[3] = {node.translation[0], node.translation[1], node.translation[2]};
        return local;
    }

    std::size_t check_node_id(int id, const std::string& referrer) const {
        if (id < 0 || std::size_t(id) >= model_.nodes.size())
            fail(referrer + " references node " + std::to_string(id) + ", file has " +
                 std::to_string(model_.nodes.size()) + " nodes");
        return std::size_t(id);
    }

    /// Places node `n`'s mesh: once at `world`, or once per EXT_mesh_gpu_instancing element
    /// at `world` times the element's T * R * S, consecutively in element order.
    void add_node_instances(std::size_t n, const Affine3d& world) {
        const tinygltf::Node& node = model_.nodes[n];
        const bool is_gpu_instanced = GltfGpuInstancing::is_used_by(model_, n);
        if (node.mesh < 0 && !is_gpu_instanced) return;
        if (node.mesh >= 0 && std::size_t(node.mesh) >= model_.meshes.size())
            fail(node_label(n) + " references missing mesh " + std::to_string(node.mesh) +
                 ", file has " + std::to_string(model_.meshes.size()) + " meshes");
        if (!is_gpu_instanced) {
            add_instance(n, kNotGpuInstanced, world);
            return;
        }
        const GltfGpuInstancing instancing(model_, n, error_prefix());
        if (instancing.count() > options_.max_instances - result_.scene.instances.size())
            fail("more than max_instances = " + std::to_string(options_.max_instances) +
                 " instances (" + node_label(n) + " adds " + std::to_string(instancing.count()) +
                 ")");
        for (std::uint64_t i = 0; i < instancing.count(); ++i)
            add_instance(n, std::uint32_t(i), world * instancing.element(i));
    }

    void add_instance(std::size_t n, std::uint32_t element, const Affine3d& world) {
        const tinygltf::Node& node = model_.nodes[n];
        const AffineTransform object_to_world = world.to_float();
        if (!object_to_world.is_finite())
            fail("instance " + std::to_string(result_.scene.instances.size()) + " (" +
                 node_label(n) +
                 (element == kNotGpuInstanced ? "" : " element " + std::to_string(element)) +
                 ") has a non-finite transform");
        if (result_.scene.instances.size() >= options_.max_instances)
            fail("more than max_instances = " + std::to_string(options_.max_instances) +
                 " instances");
        // A zero scale is how exporters hide an object: such an instance keeps its number
        // but draws the empty hidden mesh (a singular map has no inverse to trace with).
        if (is_singular_transform(object_to_world)) {
            result_.report.hidden_instances.push_back(
                std::uint32_t(result_.scene.instances.size()));
            result_.scene.instances.push_back({hidden_mesh(), AffineTransform::identity()});
        } else {
            result_.scene.instances.push_back({MeshId(node.mesh), object_to_world});
        }
        result_.report.instance_node_ids.push_back(std::uint32_t(n));
        result_.report.instance_gpu_elements.push_back(element);
        if (node.skin >= 0) ++result_.report.skinned_instance_count;
    }

    /// The empty Mesh that hidden instances use, appended on first use.
    MeshId hidden_mesh() {
        if (result_.report.hidden_mesh == kNoHiddenMesh) {
            result_.report.hidden_mesh = std::uint32_t(result_.scene.meshes.size());
            Mesh empty;
            empty.name = "hidden";
            result_.scene.meshes.push_back(std::move(empty));
        }
        return result_.report.hidden_mesh;
    }

    void add_scene_instances() {
        if (model_.scenes.empty()) fail("empty scene: the file has no scenes");
        const int scene_id = model_.defaultScene < 0 ? 0 : model_.defaultScene;
        if (model_.defaultScene < -1 || std::size_t(scene_id) >= model_.scenes.size())
            fail("invalid default scene index " + std::to_string(model_.defaultScene) +
                 ", file has " + std::to_string(model_.scenes.size()) + " scenes");
        result_.report.scene_id = std::uint32_t(scene_id);
        const tinygltf::Scene& scene = model_.scenes[std::size_t(scene_id)];
        const std::string scene_label = "scene " + std::to_string(scene_id);
        if (scene.nodes.empty()) fail("empty scene: " + scene_label + " has no nodes");

        // Iterative depth-first walk (deep hierarchies must not overflow the call stack).
        // A node reached a second time means a cycle, self-parenting or a shared child: the
        // hierarchy must be a forest, and tinygltf does not check it.
        enum class Visit : unsigned char { kNever, kOnPath, kDone };
        std::vector<Visit> visit(model_.nodes.size(), Visit::kNever);
        struct Frame {
            std::size_t node;
            std::size_t next_child;
            Affine3d world;
        };
        std::vector<Frame> path;
        constexpr std::size_t kRoot = std::numeric_limits<std::size_t>::max();
        auto enter = [&](std::size_t n, const Affine3d& parent_world, std::size_t parent) {
            const std::string from = parent == kRoot ? scene_label : node_label(parent);
            if (n == parent) fail(node_label(n) + " lists itself as a child (self-parenting)");
            if (visit[n] == Visit::kOnPath)
                fail("node cycle: " + node_label(n) + " is its own ancestor (reached again from " +
                     from + ")");
            if (visit[n] == Visit::kDone)
                fail(node_label(n) + " is reached twice in " + scene_label + " (again from " +
                     from + "): a node may have only one parent");
            visit[n] = Visit::kOnPath;
            const Affine3d world = parent_world * local_transform(n);
            add_node_instances(n, world);
            path.push_back({n, 0, world});
        };
        for (int root : scene.nodes) {
            enter(check_node_id(root, scene_label), Affine3d{}, kRoot);
            while (!path.empty()) {
                Frame& top = path.back();
                const std::vector<int>& children = model_.nodes[top.node].children;
                if (top.next_child == children.size()) {
                    visit[top.node] = Visit::kDone;
                    path.pop_back();
                    continue;
                }
                const std::size_t parent = top.node;
                const int child = children[top.next_child++];
                const Affine3d parent_world = top.world;  // `top` dies when `path` grows
                enter(check_node_id(child, node_label(parent)), parent_world, parent);
            }
        }
        if (result_.scene.instances.empty())
            fail("empty scene: no node of " + scene_label + " references a mesh");
    }

    std::string path_;
    GltfLoadOptions options_;
    tinygltf::Model model_;
    GltfLoadResult result_;
    std::uint64_t vertex_total_ = 0;
    std::uint64_t triangle_total_ = 0;
};

}  // namespace

GltfLoadResult load_gltf_scene_with_report(const std::string& path,
                                           const GltfLoadOptions& options) {
    return GltfLoader(path, options).load();
}

Scene load_gltf_scene(const std::string& path, const GltfLoadOptions& options) {
    return load_gltf_scene_with_report(path, options).scene;
}

}  // namespace rebraid
