#include "rebraid/io/gltf_scene.h"

#include <tiny_gltf.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "rebraid/core/error.h"
#include "support/gltf_test_files.h"

namespace rebraid {
namespace {

using test::GltfTestFile;
using test::primitive;

// ---- Shared scenes against their MANIFEST ------------------------------------------------------

/// One row of the shared scenes' MANIFEST.md table.
struct ManifestRow {
    std::string file;
    std::uint64_t scene_triangles = 0;
    std::uint64_t mesh_triangles = 0;
    std::uint64_t meshes = 0;
    std::uint64_t instances = 0;
};

/// Numbers in `text` in order, thousands separators removed ("216 nodes / 110" -> 216, 110).
std::vector<std::uint64_t> numbers_in(const std::string& text) {
    std::vector<std::uint64_t> numbers;
    std::string digits;
    for (std::size_t i = 0; i <= text.size(); ++i) {
        const char c = i < text.size() ? text[i] : ' ';
        const bool separator = c == ',' && !digits.empty() && i + 1 < text.size() &&
                               std::isdigit(static_cast<unsigned char>(text[i + 1]));
        if (std::isdigit(static_cast<unsigned char>(c))) {
            digits += c;
        } else if (!separator && !digits.empty()) {
            numbers.push_back(std::stoull(digits));
            digits.clear();
        }
    }
    return numbers;
}

std::vector<std::string> table_cells(const std::string& line) {
    std::vector<std::string> cells;
    std::stringstream stream(line.substr(1));
    for (std::string cell; std::getline(stream, cell, '|');) {
        const auto first = cell.find_first_not_of(' ');
        const auto last = cell.find_last_not_of(' ');
        cells.push_back(first == std::string::npos ? "" : cell.substr(first, last - first + 1));
    }
    return cells;
}

/// Parses the table: columns are found by their header ("file", "scene tris (mesh tris)",
/// "meshes", "nodes / instances"); "scene tris" alone means mesh tris are the same.
std::vector<ManifestRow> parse_manifest(const std::string& path, std::uint64_t* total_scenes) {
    std::ifstream in(path);
    std::vector<ManifestRow> rows;
    int file_col = -1, tris_col = -1, meshes_col = -1, instances_col = -1;
    for (std::string line; std::getline(in, line);) {
        if (line.rfind("Total:", 0) == 0 && !numbers_in(line).empty())
            *total_scenes = numbers_in(line)[0];
        if (line.empty() || line[0] != '|') continue;
        const std::vector<std::string> cells = table_cells(line);
        if (file_col < 0) {
            for (int c = 0; c < int(cells.size()); ++c) {
                if (cells[c] == "file") file_col = c;
                if (cells[c].find("scene tris") != std::string::npos) tris_col = c;
                if (cells[c] == "meshes") meshes_col = c;
                if (cells[c].find("instances") != std::string::npos) instances_col = c;
            }
            continue;
        }
        if (cells.empty() || cells[0].rfind("---", 0) == 0) continue;
        const int needed = std::max({file_col, tris_col, meshes_col, instances_col});
        if (tris_col < 0 || meshes_col < 0 || instances_col < 0 || int(cells.size()) <= needed)
            return {};  // unparsable: the caller fails
        const std::vector<std::uint64_t> tris = numbers_in(cells[tris_col]);
        const std::vector<std::uint64_t> meshes = numbers_in(cells[meshes_col]);
        const std::string instance_cell = cells[instances_col];
        const auto slash = instance_cell.find('/');
        const std::vector<std::uint64_t> instances =
            numbers_in(slash == std::string::npos ? "" : instance_cell.substr(slash + 1));
        if (tris.empty() || meshes.empty() || instances.empty()) return {};
        rows.push_back({cells[file_col], tris[0], tris.size() > 1 ? tris[1] : tris[0], meshes[0],
                        instances[0]});
    }
    return rows;
}

/// The manifest's "mesh tris": triangles over the distinct meshes some instance uses.
std::uint64_t referenced_mesh_triangle_count(const Scene& scene) {
    std::set<MeshId> used;
    for (const Instance& instance : scene.instances) used.insert(instance.mesh_id);
    std::uint64_t count = 0;
    for (MeshId id : used) count += scene.meshes[id].triangles.size();
    return count;
}

TEST(GltfScene, CountsMatchManifestForEverySharedScene) {
    const std::string folder = REBRAID_SHARED_SCENES;
    std::uint64_t total_scenes = 0;
    const std::vector<ManifestRow> rows = parse_manifest(folder + "/MANIFEST.md", &total_scenes);
    ASSERT_FALSE(rows.empty()) << "cannot parse " << folder << "/MANIFEST.md";
    EXPECT_EQ(rows.size(), total_scenes) << "table rows vs the manifest's 'Total:' line";
    for (const ManifestRow& row : rows) {
        SCOPED_TRACE(row.file);
        Scene scene;
        ASSERT_NO_THROW(scene = load_gltf_scene(folder + "/" + row.file));
        EXPECT_EQ(scene.instanced_triangle_count(), row.scene_triangles);
        EXPECT_EQ(referenced_mesh_triangle_count(scene), row.mesh_triangles);
        EXPECT_EQ(scene.meshes.size(), row.meshes);
        EXPECT_EQ(scene.instances.size(), row.instances);
    }
}

TEST(GltfScene, ManifestListsEverySharedSceneFile) {
    const std::string folder = REBRAID_SHARED_SCENES;
    std::uint64_t total_scenes = 0;
    std::set<std::string> listed;
    for (const ManifestRow& row : parse_manifest(folder + "/MANIFEST.md", &total_scenes))
        listed.insert(row.file);
    std::set<std::string> on_disk;
    for (const auto& entry : std::filesystem::directory_iterator(folder))
        if (entry.path().extension() == ".glb") on_disk.insert(entry.path().filename().string());
    ASSERT_FALSE(on_disk.empty());
    EXPECT_EQ(listed, on_disk);
}

// ---- Conventions on small written files -------------------------------------------------------

const std::vector<Vec3f> kFivePoints = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 1}};

/// One mesh from `primitives`, one node using it, one scene.
std::string single_mesh_file(GltfTestFile& file, const std::vector<nlohmann::json>& primitives,
                             const std::string& name) {
    file.add_mesh(primitives, "m");
    file.add_node({{"mesh", 0}});
    file.add_scene({0});
    return file.write_glb(name);
}

TEST(GltfScene, TriangleStripFollowsSpecVertexOrder) {
    GltfTestFile file;
    const int positions = file.add_positions(kFivePoints);
    const int indices = file.add_indices({2, 3, 1, 4, 0}, test::kUnsignedShort);
    const Scene scene =
        load_gltf_scene(single_mesh_file(file, {primitive(positions, indices, 5)}, "strip.glb"));
    // glTF 2.0 "Triangle Strips": p_i = {v_i, v_{i+(1+i%2)}, v_{i+(2-i%2)}} over the indices.
    const std::vector<Triangle> expected = {{2, 3, 1}, {3, 4, 1}, {1, 4, 0}};
    EXPECT_EQ(scene.meshes[0].triangles, expected);
}

TEST(GltfScene, TriangleFanFollowsSpecVertexOrder) {
    GltfTestFile file;
    const int positions = file.add_positions(kFivePoints);
    const int indices = file.add_indices({4, 0, 1, 2, 3}, test::kUnsignedByte);
    const Scene scene =
        load_gltf_scene(single_mesh_file(file, {primitive(positions, indices, 6)}, "fan.glb"));
    // glTF 2.0 "Triangle Fans": p_i = {v_{i+1}, v_{i+2}, v_0}.
    const std::vector<Triangle> expected = {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}};
    EXPECT_EQ(scene.meshes[0].triangles, expected);
}

TEST(GltfScene, MixedModesConcatenateTrianglesAndSkipPointsAndLines) {
    GltfTestFile file;
    const int tri_positions = file.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    const int quad_positions = file.add_positions({{0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}});
    const std::string path = single_mesh_file(file,
                                              {primitive(tri_positions),  // TRIANGLES, non-indexed
                                               primitive(quad_positions, -1, 0),   // POINTS
                                               primitive(quad_positions, -1, 1),   // LINES
                                               primitive(quad_positions, -1, 5),   // STRIP
                                               primitive(quad_positions, -1, 3),   // LINE_STRIP
                                               primitive(quad_positions, -1, 6)},  // FAN
                                              "mixed.glb");
    const GltfLoadResult loaded = load_gltf_scene_with_report(path);
    const Mesh& mesh = loaded.scene.meshes[0];
    // Positions of the three triangle primitives are appended: 3 + 4 + 4, offsets 0, 3, 7.
    EXPECT_EQ(mesh.positions.size(), 11u);
    const std::vector<Triangle> expected = {{0, 1, 2}, {3, 4, 5}, {4, 6, 5}, {8, 9, 7}, {9, 10, 7}};
    EXPECT_EQ(mesh.triangles, expected);
    EXPECT_EQ(mesh.positions[3], (Vec3f{0, 0, 1}));
    EXPECT_EQ(loaded.report.skipped_primitive_count(), 3u);
    EXPECT_EQ(loaded.report.primitive_count_by_mode[5], 1u);
}

TEST(GltfScene, ReportsWherePrimitivesWentAndKeepsTheModelOnRequest) {
    GltfTestFile file;
    const int tri_positions = file.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    const int quad_positions = file.add_positions({{0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}});
    nlohmann::json fan = primitive(quad_positions, -1, 6);
    fan["material"] = 0;
    const std::string path = single_mesh_file(
        file, {primitive(tri_positions), primitive(quad_positions, -1, 1), fan}, "ranges.glb");
    GltfLoadOptions options;
    options.keep_model = true;
    const GltfLoadResult loaded = load_gltf_scene_with_report(path, options);
    ASSERT_EQ(loaded.report.mesh_primitives.size(), 1u);
    const std::vector<GltfPrimitiveRange>& ranges = loaded.report.mesh_primitives[0];
    ASSERT_EQ(ranges.size(), 2u);  // the LINES primitive has no entry
    EXPECT_EQ(ranges[0].gltf_primitive, 0u);
    EXPECT_EQ(ranges[0].first_vertex, 0u);
    EXPECT_EQ(ranges[0].vertex_count, 3u);
    EXPECT_EQ(ranges[0].first_triangle, 0u);
    EXPECT_EQ(ranges[0].triangle_count, 1u);
    EXPECT_EQ(ranges[0].material, -1);
    EXPECT_EQ(ranges[1].gltf_primitive, 2u);
    EXPECT_EQ(ranges[1].first_vertex, 3u);
    EXPECT_EQ(ranges[1].vertex_count, 4u);
    EXPECT_EQ(ranges[1].first_triangle, 1u);
    EXPECT_EQ(ranges[1].triangle_count, 2u);
    EXPECT_EQ(ranges[1].material, 0);
    ASSERT_NE(loaded.model, nullptr);
    EXPECT_EQ(loaded.model->meshes.size(), 1u);
    EXPECT_EQ(load_gltf_scene_with_report(path).model, nullptr);
}

TEST(GltfScene, NonIndexedTrianglesUseConsecutiveVertices) {
    GltfTestFile file;
    std::vector<Vec3f> six(kFivePoints);
    six.push_back({3, 3, 3});
    const int positions = file.add_positions(six);
    const Scene scene =
        load_gltf_scene(single_mesh_file(file, {primitive(positions)}, "nonindexed.glb"));
    const std::vector<Triangle> expected = {{0, 1, 2}, {3, 4, 5}};
    EXPECT_EQ(scene.meshes[0].triangles, expected);
    EXPECT_EQ(scene.meshes[0].positions, six);
}

TEST(GltfScene, DegenerateTrianglesAreKept) {
    GltfTestFile file;
    const int positions = file.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    const int indices = file.add_indices({0, 0, 1, 0, 1, 2});
    const Scene scene =
        load_gltf_scene(single_mesh_file(file, {primitive(positions, indices)}, "degen.glb"));
    EXPECT_EQ(scene.meshes[0].triangles.size(), 2u);
}

TEST(GltfScene, HonoursAccessorAndBufferViewOffsetsAndStride) {
    GltfTestFile file;
    file.add_view("pad!", 4);  // the interleaved view starts at byte 4 of the buffer
    // Interleaved records of 5 floats: 2 floats of something else, then x y z.
    const float records[3][5] = {{9, 9, 1, 2, 3}, {9, 9, 4, 5, 6}, {9, 9, 7, 8, 9}};
    const int view = file.add_view(records, sizeof records, 5 * sizeof(float));
    const int positions = file.add_accessor(view, test::kFloat, 3, "VEC3", 2 * sizeof(float));
    const std::uint16_t index_words[4] = {7, 2, 1, 0};  // first word skipped by byteOffset
    const int index_view = file.add_view(index_words, sizeof index_words);
    const int indices = file.add_accessor(index_view, test::kUnsignedShort, 3, "SCALAR", 2);
    const Scene scene =
        load_gltf_scene(single_mesh_file(file, {primitive(positions, indices)}, "interleaved.glb"));
    const std::vector<Vec3f> expected_positions = {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}};
    EXPECT_EQ(scene.meshes[0].positions, expected_positions);
    EXPECT_EQ(scene.meshes[0].triangles, (std::vector<Triangle>{{2, 1, 0}}));
}

TEST(GltfScene, LoadsGltfWithExternalBuffer) {
    GltfTestFile file;
    const int positions = file.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    file.add_mesh({primitive(positions)});
    file.add_node({{"mesh", 0}});
    file.add_scene({0});
    const Scene scene = load_gltf_scene(file.write_gltf("external.gltf"));
    EXPECT_EQ(scene.meshes[0].triangles.size(), 1u);
    EXPECT_EQ(scene.meshes[0].positions[1], (Vec3f{1, 0, 0}));
}

void expect_near(Vec3f actual, Vec3f expected) {
    EXPECT_NEAR(actual.x, expected.x, 1e-5f);
    EXPECT_NEAR(actual.y, expected.y, 1e-5f);
    EXPECT_NEAR(actual.z, expected.z, 1e-5f);
}

/// A file with one triangle mesh and the given nodes, scene roots `roots`.
GltfTestFile triangle_with_nodes(const std::vector<nlohmann::json>& nodes,
                                 const std::vector<int>& roots) {
    GltfTestFile file;
    file.add_mesh({primitive(file.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}))});
    for (const nlohmann::json& node : nodes) file.add_node(node);
    file.add_scene(roots);
    return file;
}

TEST(GltfScene, MatrixAndTrsGiveTheSameTransform) {
    const double h = std::sqrt(0.5);  // quaternion of 90 degrees about +z: (0, 0, h, h)
    const GltfTestFile file = triangle_with_nodes(
        {{{"mesh", 0},
          {"translation", {1, 2, 3}},
          {"rotation", {0, 0, h, h}},
          {"scale", {2, 3, 4}}},
         // The same map as a column-major matrix: columns R*S*e_x, R*S*e_y, R*S*e_z, T.
         {{"mesh", 0}, {"matrix", {0, 2, 0, 0, -3, 0, 0, 0, 0, 0, 4, 0, 1, 2, 3, 1}}}},
        {0, 1});
    const Scene scene = load_gltf_scene(file.write_glb("trs.glb"));
    ASSERT_EQ(scene.instances.size(), 2u);
    // (1,1,1) -> scale (2,3,4) -> rotate (-3,2,4) -> translate (-2,4,7).
    for (const Instance& instance : scene.instances)
        expect_near(instance.object_to_world.transform_point({1, 1, 1}), {-2, 4, 7});
}

TEST(GltfScene, NestedTransformsApplyParentAfterChild) {
    const double h = std::sqrt(0.5);
    const GltfTestFile file = triangle_with_nodes(
        {{{"translation", {10, 0, 0}}, {"rotation", {0, 0, h, h}}, {"children", {1}}},
         {{"mesh", 0}, {"translation", {1, 0, 0}}, {"scale", {2, 2, 2}}}},
        {0});
    const Scene scene = load_gltf_scene(file.write_glb("nested.glb"));
    ASSERT_EQ(scene.instances.size(), 1u);
    // Child: (1,0,0) -> (2,0,0) -> (3,0,0); parent: rotate -> (0,3,0), translate -> (10,3,0).
    expect_near(scene.instances[0].object_to_world.transform_point({1, 0, 0}), {10, 3, 0});
}

TEST(GltfScene, InstancesAreNumberedDepthFirst) {
    GltfTestFile file;
    const int positions = file.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    for (int m = 0; m < 6; ++m) file.add_mesh({primitive(positions)}, "mesh" + std::to_string(m));
    // Roots [3, 0]; 3 -> [1], 1 -> [4, 2], 2 (no mesh) -> [5]. Node n uses mesh n.
    file.add_node({{"mesh", 0}});
    file.add_node({{"mesh", 1}, {"children", {4, 2}}});
    file.add_node({{"children", {5}}});
    file.add_node({{"mesh", 3}, {"children", {1}}});
    file.add_node({{"mesh", 4}});
    file.add_node({{"mesh", 5}});
    file.add_scene({3, 0});
    const GltfLoadResult loaded = load_gltf_scene_with_report(file.write_glb("dfs.glb"));
    const std::vector<std::uint32_t> expected_nodes = {3, 1, 4, 5, 0};
    EXPECT_EQ(loaded.report.instance_node_ids, expected_nodes);
    ASSERT_EQ(loaded.scene.instances.size(), expected_nodes.size());
    for (std::size_t i = 0; i < expected_nodes.size(); ++i)
        EXPECT_EQ(loaded.scene.instances[i].mesh_id, expected_nodes[i]);
    // Mesh ids are glTF mesh ids, including mesh 2 that no node uses.
    ASSERT_EQ(loaded.scene.meshes.size(), 6u);
    EXPECT_EQ(loaded.scene.meshes[2].name, "mesh2");
}

TEST(GltfScene, UsesTheDefaultSceneProperty) {
    GltfTestFile file = triangle_with_nodes({{{"mesh", 0}}, {{"mesh", 0}}, {{"mesh", 0}}}, {0});
    file.add_scene({1, 2});
    EXPECT_EQ(load_gltf_scene(file.write_glb("scene_unset.glb")).instances.size(), 1u);
    file.json["scene"] = 1;
    const GltfLoadResult loaded = load_gltf_scene_with_report(file.write_glb("scene_one.glb"));
    EXPECT_EQ(loaded.report.scene_id, 1u);
    EXPECT_EQ(loaded.report.instance_node_ids, (std::vector<std::uint32_t>{1, 2}));
}

TEST(GltfScene, IgnoresSkinsAndMorphTargets) {
    GltfTestFile file;
    const int positions = file.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    const int deltas = file.add_positions({{5, 5, 5}, {5, 5, 5}, {5, 5, 5}});
    nlohmann::json morphed = primitive(positions);
    morphed["targets"] = {{{"POSITION", deltas}}};
    file.add_mesh({morphed});
    file.json["meshes"][0]["weights"] = {1.0};
    file.add_node({{"mesh", 0}, {"skin", 0}, {"translation", {0, 0, 2}}});
    file.add_node({{"translation", {7, 0, 0}}});
    file.json["skins"] = {{{"joints", {1}}}};
    file.add_scene({0, 1});
    const GltfLoadResult loaded = load_gltf_scene_with_report(file.write_glb("skin.glb"));
    EXPECT_EQ(loaded.scene.meshes[0].positions[1], (Vec3f{1, 0, 0}));  // rest positions
    expect_near(loaded.scene.instances[0].object_to_world.transform_point({0, 0, 0}), {0, 0, 2});
    EXPECT_EQ(loaded.report.skinned_instance_count, 1u);
    EXPECT_EQ(loaded.report.morphed_primitive_count, 1u);
}

// ---- Bad input ------------------------------------------------------------------------------

/// Loading `path` throws rebraid::Error whose message names the file and contains `phrase`.
void expect_load_error(const std::string& path, const std::string& phrase,
                       const GltfLoadOptions& options = {}) {
    try {
        load_gltf_scene(path, options);
        ADD_FAILURE() << "no error loading " << path << " (expected '" << phrase << "')";
    } catch (const Error& error) {
        const std::string message = error.what();
        EXPECT_NE(message.find(phrase), std::string::npos) << message;
        EXPECT_NE(message.find(path), std::string::npos) << message;
    }
}

/// A valid one-triangle file that tests then break.
GltfTestFile valid_file() {
    return triangle_with_nodes({{{"mesh", 0}}}, {0});
}

std::string read_whole(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(GltfSceneErrors, MissingFile) {
    expect_load_error(test::scratch_path("does_not_exist.glb"), "no such file");
}

TEST(GltfSceneErrors, MalformedJsonIncludesParserText) {
    expect_load_error(test::write_scratch_file("garbage.gltf", "{ \"asset\": [1, 2"),
                      "malformed glTF: ");
    expect_load_error(test::write_scratch_file("empty.gltf", ""), "empty");
}

TEST(GltfSceneErrors, TruncatedGlb) {
    const std::string whole = read_whole(valid_file().write_glb("whole.glb"));
    for (std::size_t keep : {std::size_t(10), std::size_t(24), whole.size() / 2, whole.size() - 4})
        expect_load_error(test::write_scratch_file("truncated.glb", whole.substr(0, keep)),
                          "truncated");
}

TEST(GltfSceneErrors, AccessorPastItsBufferView) {
    GltfTestFile file = valid_file();
    file.json["accessors"][0]["count"] = 4;
    expect_load_error(file.write_glb("accessor_past.glb"), "past the end of bufferView 0");
    file.json["accessors"][0]["count"] = 3;
    file.json["accessors"][0]["byteOffset"] = 4;
    expect_load_error(file.write_glb("accessor_offset_past.glb"), "past the end of bufferView");
}

TEST(GltfSceneErrors, BufferViewPastItsBuffer) {
    GltfTestFile file = valid_file();
    file.json["bufferViews"][0]["byteOffset"] = 4;
    expect_load_error(file.write_glb("view_past.glb"), "past the end of buffer 0");
}

TEST(GltfSceneErrors, HugeDeclaredCountsAreRejectedBeforeAllocating) {
    GltfTestFile file = valid_file();
    file.json["accessors"][0]["count"] = std::uint64_t(1) << 40;
    expect_load_error(file.write_glb("huge_count.glb"), "past the end of bufferView");
    file.json["accessors"][0]["count"] = std::numeric_limits<std::uint64_t>::max() / 2;
    expect_load_error(file.write_glb("huge_count_overflow.glb"), "past the end of bufferView");
}

TEST(GltfSceneErrors, TriangleAndVertexLimits) {
    const std::string path = valid_file().write_glb("limits.glb");
    expect_load_error(path, "max_triangles", {.max_triangles = 0});
    expect_load_error(path, "max_vertices", {.max_vertices = 2});
}

TEST(GltfSceneErrors, IndexPastTheVertexCount) {
    GltfTestFile file;
    const int positions = file.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    const int indices = file.add_indices({0, 1, 2, 2, 1, 7});
    expect_load_error(single_mesh_file(file, {primitive(positions, indices)}, "index_past.glb"),
                      "triangle 1 of mesh 0 ('m') primitive 0 uses vertex 7, the primitive has 3");
}

TEST(GltfSceneErrors, NonFiniteVertexPosition) {
    for (float bad :
         {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        GltfTestFile file;
        const int positions = file.add_positions({{0, 0, 0}, {1, bad, 0}, {0, 1, 0}});
        expect_load_error(single_mesh_file(file, {primitive(positions)}, "nonfinite.glb"),
                          "vertex 1 position is not finite");
    }
}

TEST(GltfSceneErrors, NodeCycleSelfParentingAndSharedChild) {
    expect_load_error(
        triangle_with_nodes({{{"mesh", 0}, {"children", {1}}}, {{"children", {0}}}}, {0})
            .write_glb("cycle.glb"),
        "node cycle");
    expect_load_error(
        triangle_with_nodes({{{"mesh", 0}, {"children", {0}}}}, {0}).write_glb("self.glb"),
        "lists itself as a child");
    expect_load_error(
        triangle_with_nodes({{{"children", {2}}}, {{"children", {2}}}, {{"mesh", 0}}}, {0, 1})
            .write_glb("shared_child.glb"),
        "node 2 ('') is reached twice");
    expect_load_error(triangle_with_nodes({{{"mesh", 0}}}, {0, 0}).write_glb("root_twice.glb"),
                      "reached twice");
    expect_load_error(
        triangle_with_nodes({{{"mesh", 0}, {"children", {5}}}}, {0}).write_glb("missing_child.glb"),
        "references node 5");
}

TEST(GltfSceneErrors, NodeReferencesMissingMesh) {
    expect_load_error(triangle_with_nodes({{{"mesh", 3}}}, {0}).write_glb("missing_mesh.glb"),
                      "references missing mesh 3");
}

TEST(GltfSceneErrors, InvalidDefaultSceneIndex) {
    GltfTestFile file = valid_file();
    file.json["scene"] = 2;
    expect_load_error(file.write_glb("bad_scene_index.glb"), "invalid default scene index 2");
}

TEST(GltfSceneErrors, EmptyScene) {
    GltfTestFile no_scenes = valid_file();
    no_scenes.json.erase("scenes");
    expect_load_error(no_scenes.write_glb("no_scenes.glb"), "empty scene");
    expect_load_error(triangle_with_nodes({{{"mesh", 0}}}, {}).write_glb("no_roots.glb"),
                      "empty scene");
    expect_load_error(triangle_with_nodes({{{"name", "camera"}}}, {0}).write_glb("no_meshes.glb"),
                      "empty scene");
}

TEST(GltfScene, SingularNodeTransformHidesTheInstance) {
    const GltfLoadResult loaded = load_gltf_scene_with_report(
        triangle_with_nodes({{{"mesh", 0}, {"scale", {1, 0, 1}}}, {{"mesh", 0}}}, {0, 1})
            .write_glb("singular.glb"));
    ASSERT_EQ(loaded.scene.instances.size(), 2u);
    EXPECT_EQ(loaded.report.hidden_instances, std::vector<std::uint32_t>{0});
    EXPECT_EQ(loaded.scene.instances[0].mesh_id, loaded.report.hidden_mesh);
    EXPECT_TRUE(loaded.scene.meshes.at(loaded.report.hidden_mesh).triangles.empty());
    EXPECT_EQ(loaded.scene.instances[1].mesh_id, 0u);
}

TEST(GltfSceneErrors, NonFiniteNodeTransform) {
    // Finite in the file, but not as a float.
    expect_load_error(triangle_with_nodes({{{"mesh", 0}, {"translation", {1e39, 0, 0}}}}, {0})
                          .write_glb("overflow.glb"),
                      "non-finite transform");
    // Finite in double, infinite once parent and child scales multiply.
    expect_load_error(triangle_with_nodes({{{"scale", {1e200, 1, 1}}, {"children", {1}}},
                                           {{"mesh", 0}, {"scale", {1e200, 1, 1}}}},
                                          {0})
                          .write_glb("overflow_nested.glb"),
                      "non-finite transform");
    expect_load_error(triangle_with_nodes({{{"mesh", 0}, {"matrix", {1, 0, 0}}}}, {0})
                          .write_glb("short_matrix.glb"),
                      "expected 16");
}

TEST(GltfSceneErrors, UnsupportedAccessors) {
    GltfTestFile sparse = valid_file();
    sparse.json["accessors"][0]["sparse"] = {
        {"count", 1},
        {"indices", {{"bufferView", 0}, {"componentType", test::kUnsignedByte}}},
        {"values", {{"bufferView", 0}}}};
    expect_load_error(sparse.write_glb("sparse.glb"), "sparse accessors not supported");
    GltfTestFile vec2 = valid_file();
    vec2.json["accessors"][0]["type"] = "VEC2";
    expect_load_error(vec2.write_glb("vec2.glb"), "must be a float, byte or short VEC3 accessor");
    GltfTestFile no_position = valid_file();
    no_position.json["meshes"][0]["primitives"][0]["attributes"] = {{"NORMAL", 0}};
    expect_load_error(no_position.write_glb("no_position.glb"), "no POSITION attribute");
    GltfTestFile float_indices = valid_file();
    float_indices.json["meshes"][0]["primitives"][0]["indices"] = 0;
    expect_load_error(float_indices.write_glb("float_indices.glb"), "unsigned byte, short or int");
}

TEST(GltfSceneErrors, IndexCountDoesNotFitTheTopology) {
    GltfTestFile file;
    const int positions = file.add_positions(kFivePoints);
    const int four = file.add_indices({0, 1, 2, 3});
    const int two = file.add_indices({0, 1});
    file.add_mesh({primitive(positions, four)});
    file.add_mesh({primitive(positions, two, 5)});
    file.add_node({{"mesh", 0}});
    file.add_scene({0});
    expect_load_error(file.write_glb("not_multiple_of_3.glb"), "multiple of 3");
    file.json["meshes"][0] = file.json["meshes"][1];  // mesh 0 becomes the 2-index strip
    expect_load_error(file.write_glb("short_strip.glb"), "3 or more vertex indices");
}

}  // namespace
}  // namespace rebraid
