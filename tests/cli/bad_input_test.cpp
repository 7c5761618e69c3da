// Bad input corpus: every kind of broken or hostile input that
// gltf_scene_test.cpp and ray_file_test.cpp do not already cover, fed through the `rebraid`
// command (exit code 1 and a message naming the problem) or the library (rebraid::Error), or
// checked against its documented handling. The files are generated here; nothing binary is
// committed. docs/testing.md lists every case and where it is tested.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "embree_glue/reference/embree_reference.h"
#include "rebraid/core/error.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/rebraiding/rebraid_builder.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/instanced_accel.h"
#include "support/cli_runner.h"
#include "support/gltf_test_files.h"
#include "support/own_structures.h"

namespace rebraid {
namespace {

namespace fs = std::filesystem;
using test::CommandResult;

fs::path scratch_dir() {
    return test::test_scratch_dir("bad_input_test");
}

/// Runs `rebraid` under a 120 s timeout: a hang fails instead of blocking the suite.
CommandResult run_rebraid(const std::vector<std::string>& arguments) {
    return test::run_rebraid_in(scratch_dir(), arguments, 120);
}
using test::GltfTestFile;
using test::primitive;

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// ---- Running the command ------------------------------------------------------------------

/// The command fails cleanly: exit code 1 (not a crash, not the timeout's 124) and one
/// `rebraid: ` message containing every phrase.
void expect_clean_failure(const std::vector<std::string>& arguments,
                          std::initializer_list<std::string> phrases) {
    const CommandResult result = run_rebraid(arguments);
    std::string joined;
    for (const std::string& argument : arguments) joined += argument + " ";
    EXPECT_EQ(result.exit_code, 1) << joined << "\n" << result.err;
    EXPECT_EQ(result.err.rfind("rebraid: ", 0), 0u) << joined << "\n" << result.err;
    for (const std::string& phrase : phrases)
        EXPECT_NE(result.err.find(phrase), std::string::npos)
            << joined << ": no '" << phrase << "' in\n"
            << result.err;
}

/// A one-triangle file (mesh 0, node 0, scene 0) that tests then break.
GltfTestFile one_triangle_file() {
    GltfTestFile file;
    file.add_mesh({primitive(file.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}))});
    file.add_node({{"mesh", 0}});
    file.add_scene({0});
    return file;
}

std::string scratch_glb(const GltfTestFile& file, const std::string& name) {
    const fs::path dir = scratch_dir();
    // write_glb writes into the glTF writer's scratch folder; move it to our folder.
    const fs::path written = file.write_glb("bad_input_" + name);
    const fs::path path = dir / name;
    fs::rename(written, path);
    return path.string();
}

/// The one-triangle scene in the test's folder: commands given it start fast (the default
/// scene would be built otherwise).
std::string tiny_scene() {
    return scratch_glb(one_triangle_file(), "tiny.glb");
}

// ---- glTF files through the command -------------------------------------------------------

TEST(BadInputCli, BrokenGltfFilesExitWithOneAndNameTheProblem) {
    const fs::path dir = scratch_dir();
    // Cases the loader tests cover through the library; here the command must report them.
    const std::string whole =
        test::read_text_file(scratch_glb(one_triangle_file(), "whole_for_truncation.glb"));
    test::write_text_file(dir / "truncated.glb", whole.substr(0, whole.size() / 2));
    expect_clean_failure({"stats", (dir / "truncated.glb").string()}, {"truncated GLB"});
    test::write_text_file(dir / "broken.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [");
    expect_clean_failure({"stats", (dir / "broken.gltf").string()}, {"malformed glTF"});

    GltfTestFile past_buffer = one_triangle_file();
    past_buffer.json["accessors"][0]["count"] = 1000;
    expect_clean_failure({"stats", scratch_glb(past_buffer, "past.glb")},
                         {"past the end of bufferView"});

    GltfTestFile nan_position;
    nan_position.add_mesh(
        {primitive(nan_position.add_positions({{0, 0, 0}, {kNaN, 0, 0}, {0, 1, 0}}))});
    nan_position.add_node({{"mesh", 0}});
    nan_position.add_scene({0});
    expect_clean_failure({"stats", scratch_glb(nan_position, "nan.glb")},
                         {"vertex 1 position is not finite"});

    GltfTestFile cycle = one_triangle_file();
    cycle.json["nodes"][0]["children"] = {1};
    cycle.add_node({{"children", {0}}});
    expect_clean_failure(
        {"render", scratch_glb(cycle, "cycle.glb"), "-o", (dir / "never.png").string()},
        {"node cycle"});
}

TEST(BadInputCli, SingularNodeTransformsHideTheInstance) {
    // A zero scale hides an object: the instance keeps its number and draws nothing.
    GltfTestFile singular = one_triangle_file();
    singular.json["nodes"][0]["matrix"] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};
    GltfTestFile tiny_scale = one_triangle_file();
    tiny_scale.json["nodes"][0]["scale"] = {1e-20, 1e-20, 1e-20};  // determinant 1e-60
    for (const std::string& path :
         {scratch_glb(singular, "singular.glb"), scratch_glb(tiny_scale, "tiny_scale.glb")}) {
        const CommandResult result = run_rebraid({"stats", path});
        EXPECT_EQ(result.exit_code, 0) << result.err;
        EXPECT_NE(result.out.find("instances       1\n"), std::string::npos) << result.out;
        EXPECT_NE(result.out.find("triangles       0\n"), std::string::npos) << result.out;
        expect_clean_failure({"render", path, "-o", (scratch_dir() / "never.png").string()},
                             {"no triangles"});
    }
}

TEST(BadInputCli, NonFiniteAndDegenerateNodeTransformsExitWithOne) {
    GltfTestFile zero_quaternion = one_triangle_file();
    zero_quaternion.json["nodes"][0]["rotation"] = {0, 0, 0, 0};
    expect_clean_failure({"stats", scratch_glb(zero_quaternion, "zero_quaternion.glb")},
                         {"zero rotation quaternion"});
    GltfTestFile projective = one_triangle_file();
    projective.json["nodes"][0]["matrix"] = {1, 0, 0, 0.5, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    expect_clean_failure({"stats", scratch_glb(projective, "projective.glb")},
                         {"bottom row is not (0, 0, 0, 1)"});
}

TEST(BadInputCli, MemoryBombsAreRejectedBeforeAllocating) {
    // A buffer declaring a terabyte: the BIN chunk is small, so it must not be allocated.
    GltfTestFile huge_buffer = one_triangle_file();
    huge_buffer.json["buffers"] = {{{"byteLength", std::uint64_t(1) << 40}}};
    expect_clean_failure({"stats", scratch_glb(huge_buffer, "huge_buffer.glb")},
                         {"malformed glTF"});
    // A bufferView declaring a terabyte inside a small buffer.
    GltfTestFile huge_view = one_triangle_file();
    huge_view.json["bufferViews"][0]["byteLength"] = std::uint64_t(1) << 40;
    expect_clean_failure({"stats", scratch_glb(huge_view, "huge_view.glb")},
                         {"past the end of buffer 0"});
    // Accessor counts that overflow 64-bit byte arithmetic (count x stride).
    GltfTestFile overflow = one_triangle_file();
    overflow.json["accessors"][0]["count"] = std::uint64_t(1) << 62;
    overflow.json["bufferViews"][0]["byteStride"] = 12;
    expect_clean_failure({"stats", scratch_glb(overflow, "overflow.glb")},
                         {"past the end of bufferView"});
    // The GLB header claims 4 GiB.
    std::string whole =
        test::read_text_file(scratch_glb(one_triangle_file(), "whole_for_4gib_claim.glb"));
    const std::uint32_t claimed = 0xffffffffu;
    whole.replace(8, 4, reinterpret_cast<const char*>(&claimed), 4);
    test::write_text_file(scratch_dir() / "claims_4gib.glb", whole);
    expect_clean_failure({"stats", (scratch_dir() / "claims_4gib.glb").string()},
                         {"truncated GLB"});
}

TEST(BadInputCli, ExternalBufferThatIsMissingOrADeviceIsAnError) {
    const fs::path dir = scratch_dir();
    GltfTestFile file = one_triangle_file();
    nlohmann::json json = file.json;
    json["buffers"] = {{{"byteLength", file.bin.size()}, {"uri", "no_such_file.bin"}}};
    test::write_text_file(dir / "missing_bin.gltf", json.dump());
    expect_clean_failure({"stats", (dir / "missing_bin.gltf").string()}, {"malformed glTF"});
    // A uri naming an endless device must not hang or fill memory.
    json["buffers"] = {{{"byteLength", file.bin.size()}, {"uri", "/dev/zero"}}};
    test::write_text_file(dir / "dev_zero.gltf", json.dump());
    expect_clean_failure({"stats", (dir / "dev_zero.gltf").string()}, {"malformed glTF"});
    // A directory given as the scene.
    expect_clean_failure({"stats", dir.string()}, {dir.string()});
}

TEST(BadInputCli, DeeplyNestedJsonDoesNotOverflowTheStack) {
    const fs::path dir = scratch_dir();
    const std::size_t depth = 200000;
    std::string nested = "{\"asset\": {\"version\": \"2.0\"}, \"extras\": ";
    nested += std::string(depth, '[') + std::string(depth, ']') + "}";
    test::write_text_file(dir / "nested.gltf", nested);
    const CommandResult result = run_rebraid({"stats", (dir / "nested.gltf").string()});
    EXPECT_EQ(result.exit_code, 1) << result.err;  // no scene in it, whatever the parser does
}

TEST(BadInputCli, DeepNodeHierarchyLoads) {
    // 100,000 nested nodes: the walk is iterative, so this is a valid (if silly) scene.
    GltfTestFile file;
    file.add_mesh({primitive(file.add_positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}))});
    const int depth = 100000;
    for (int n = 0; n < depth; ++n) {
        nlohmann::json node = {{"translation", {0.0, 0.0, 1e-5}}};
        if (n + 1 < depth) node["children"] = {n + 1};
        if (n + 1 == depth) node["mesh"] = 0;
        file.add_node(node);
    }
    file.add_scene({0});
    const CommandResult result = run_rebraid({"stats", scratch_glb(file, "deep.glb"), "--json"});
    EXPECT_EQ(result.exit_code, 0) << result.err;
    EXPECT_NE(result.out.find("\"instances\": 1"), std::string::npos) << result.out;
}

TEST(BadInputCli, MeshWithoutPrimitivesOrTrianglesIsHandled) {
    // "primitives": [] breaks the glTF schema (minItems 1): an error naming the problem, or
    // an empty mesh; either way no crash. Only the second is accepted by tinygltf 2.7, so the
    // scene then has one instance of an empty mesh beside a normal one.
    GltfTestFile no_primitives = one_triangle_file();
    no_primitives.json["meshes"].push_back({{"primitives", nlohmann::json::array()}});
    no_primitives.add_node({{"mesh", 1}});
    no_primitives.json["scenes"][0]["nodes"] = {0, 1};
    const std::string path = scratch_glb(no_primitives, "no_primitives.glb");
    for (const char* accel : {"embree-flat", "embree-instanced", "flat", "twolevel", "rebraid"}) {
        const CommandResult result = run_rebraid({"stats", path, "--accel", accel, "--json"});
        // 0 or 1 only: under `timeout` a crash shows as 128 + signal, a hang as 124.
        ASSERT_TRUE(result.exit_code == 0 || result.exit_code == 1)
            << accel << " exited with " << result.exit_code << "\n"
            << result.err;
        if (result.exit_code == 0) {
            EXPECT_NE(result.out.find("\"triangles\": 1,"), std::string::npos) << result.out;
            EXPECT_NE(result.out.find("\"instances\": 2,"), std::string::npos) << result.out;
        } else {
            EXPECT_EQ(result.exit_code, 1) << result.err;
            EXPECT_NE(result.err.find("primitives"), std::string::npos) << result.err;
        }
    }
}

// ---- Scenes with nothing to hit -------------------------------------------------------------

/// A mesh whose triangles are all degenerate: repeated corners (zero length) and collinear
/// corners (zero area).
Mesh degenerate_mesh() {
    Mesh mesh;
    mesh.name = "degenerate";
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 0, 0}, {1, 1, 3}, {0, 1, 2}, {3, 3, 0}};
    return mesh;
}

/// Every structure the project has, built over `scene`: Embree's two and our own.
test::NamedAccels every_structure(const Scene& scene) {
    test::NamedAccels structures;
    structures.emplace_back("embree-flat", std::make_unique<glue::EmbreeFlatAccel>(scene));
    structures.emplace_back("embree-instanced",
                            std::make_unique<glue::EmbreeInstancedAccel>(scene));
    for (auto& named : test::own_structures(scene, 100.0f)) structures.push_back(std::move(named));
    return structures;
}

/// Rays from all around the origin towards it, plus rays along the degenerate triangles'
/// lines, where a careless test would report a hit.
std::vector<Ray> rays_at_origin() {
    std::vector<Ray> rays;
    for (int i = 0; i < 64; ++i) {
        const float a = float(i) * 0.7f, b = float(i) * 1.3f;
        const Vec3f dir{std::cos(a) * std::sin(b), std::sin(a) * std::sin(b), std::cos(b)};
        rays.push_back({dir * -5.0f + Vec3f{0.5f, 0.1f, 0.0f}, 0.0f, dir, kInf});
    }
    rays.push_back({{-1, 0, 0}, 0.0f, {1, 0, 0}, kInf});     // along the x axis: the segments
    rays.push_back({{0, 0, -1}, 0.0f, {0, 0, 1}, kInf});     // through the point (0, 0, 0)
    rays.push_back({{1, 0.5f, -1}, 0.0f, {0, 0, 1}, kInf});  // through the line (1,0,0)-(0,1,0)
    return rays;
}

TEST(BadInputScene, DegenerateTrianglesAreNeverHitByAnyStructure) {
    Scene scene;
    scene.meshes.push_back(degenerate_mesh());
    scene.instances.push_back({0, AffineTransform::identity()});
    scene.instances.push_back({0, AffineTransform::translate({0, 0, 1})});
    for (const auto& [name, accel] : every_structure(scene))
        for (const Ray& ray : rays_at_origin()) {
            EXPECT_FALSE(accel->intersect(ray).is_hit()) << name;
            EXPECT_FALSE(accel->occluded(ray)) << name;
        }
}

TEST(BadInputScene, EmptyMeshesAndSceneWithoutTrianglesBuildAndMiss) {
    Scene scene;
    scene.meshes.emplace_back().name = "empty";
    Mesh no_triangles;
    no_triangles.name = "no triangles";
    no_triangles.positions = {{1, 2, 3}};
    scene.meshes.push_back(no_triangles);
    scene.instances.push_back({0, AffineTransform::identity()});
    scene.instances.push_back({1, AffineTransform::translate({1, 0, 0})});
    for (const auto& [name, accel] : every_structure(scene)) {
        for (const Ray& ray : rays_at_origin())
            EXPECT_FALSE(accel->intersect(ray).is_hit()) << name;
        EXPECT_EQ(accel->stats().triangles, 0u) << name;
        EXPECT_EQ(accel->stats().instances, 2u) << name;
    }
    // No instances at all.
    const Scene nothing;
    for (const auto& [name, accel] : every_structure(nothing))
        EXPECT_FALSE(accel->intersect(rays_at_origin()[0]).is_hit()) << name;
}

TEST(BadInputScene, InvalidScenesAreRejectedByEveryBuilder) {
    Scene good;
    good.meshes.push_back(degenerate_mesh());
    good.meshes[0].triangles.push_back({0, 1, 3});
    good.instances.push_back({0, AffineTransform::identity()});
    const std::vector<std::pair<std::string, std::function<void(Scene&)>>> breakages = {
        {"not finite", [](Scene& s) { s.meshes[0].positions[1].y = kNaN; }},
        {"not finite", [](Scene& s) { s.meshes[0].positions[2].z = -kInf; }},
        {"uses vertex 9", [](Scene& s) { s.meshes[0].triangles[0][1] = 9; }},
        {"references mesh 4", [](Scene& s) { s.instances[0].mesh_id = 4; }},
        {"non-finite transform", [](Scene& s) { s.instances[0].object_to_world.col_y.x = kNaN; }},
        {"non-finite transform",
         [](Scene& s) { s.instances[0].object_to_world.translation.z = kInf; }},
        {"singular transform",
         [](Scene& s) {
             s.instances[0].object_to_world = AffineTransform::scale({1, 1, 0});
         }},
        {"singular transform",  // finite entries, determinant below float range
         [](Scene& s) {
             s.instances[0].object_to_world = AffineTransform::scale({1e-15f, 1e-15f, 1e-15f});
         }},
    };
    for (const auto& [phrase, breakage] : breakages) {
        Scene bad = good;
        breakage(bad);
        const std::vector<std::pair<std::string, std::function<void()>>> builders = {
            {"embree-flat", [&] { glue::EmbreeFlatAccel accel(bad); }},
            {"embree-instanced", [&] { glue::EmbreeInstancedAccel accel(bad); }},
            {"flat", [&] { FlatAccel accel(bad); }},
            {"twolevel", [&] { (void)build_two_level_accel(bad); }},
            {"rebraid", [&] { (void)build_rebraid_accel(bad); }},
        };
        for (const auto& [name, build] : builders) {
            try {
                build();
                ADD_FAILURE() << name << " accepted a scene with '" << phrase << "'";
            } catch (const Error& error) {
                EXPECT_NE(std::string(error.what()).find(phrase), std::string::npos)
                    << name << ": " << error.what();
            }
        }
    }
}

// ---- Rays ---------------------------------------------------------------------------------

TEST(BadInputRays, EmptySegmentsMissInEveryStructure) {
    Scene scene;
    Mesh quad;
    quad.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    quad.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(quad);
    scene.instances.push_back({0, AffineTransform::identity()});
    const Ray through{{0.1f, 0.2f, 5}, 0.0f, {0, 0, -1}, kInf};
    Ray reversed = through;  // tnear > tfar: documented as an empty segment, a miss
    reversed.tnear = 6.0f;
    reversed.tfar = 4.0f;
    Ray stops_short = through;
    stops_short.tfar = 4.0f;
    Ray starts_late = through;
    starts_late.tnear = 5.5f;
    for (const auto& [name, accel] : every_structure(scene)) {
        EXPECT_TRUE(accel->intersect(through).is_hit()) << name;  // the check can fail
        for (const Ray& ray : {reversed, stops_short, starts_late}) {
            EXPECT_FALSE(accel->intersect(ray).is_hit()) << name;
            EXPECT_FALSE(accel->occluded(ray)) << name;
        }
    }
}

TEST(BadInputRays, NonFiniteOrZeroDirectionRaysNeitherCrashNorHang) {
    // The project's own structures take any ray: they must answer (a miss, since no segment
    // of such a ray is well defined) without crashing or looping. The Embree references
    // document that they throw instead (Embree's assertions would abort the process).
    Scene scene;
    Mesh quad;
    quad.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    quad.triangles = {{0, 1, 2}, {0, 2, 3}};
    scene.meshes.push_back(quad);
    scene.instances.push_back({0, AffineTransform::identity()});
    scene.instances.push_back({0, AffineTransform::scale({-2, 1, 1})});  // mirrored
    const std::vector<Ray> bad_rays = {
        {{0, 0, 5}, 0.0f, {kNaN, 0, -1}, kInf}, {{kNaN, 0, 5}, 0.0f, {0, 0, -1}, kInf},
        {{0, 0, 5}, 0.0f, {0, 0, 0}, kInf},     {{0, 0, 5}, 0.0f, {kInf, 0, -1}, kInf},
        {{kInf, 0, 5}, 0.0f, {0, 0, -1}, kInf}, {{0, 0, 5}, kNaN, {0, 0, -1}, kInf},
        {{0, 0, 5}, 0.0f, {0, 0, -1}, kNaN},
    };
    for (const auto& [name, accel] : every_structure(scene)) {
        const bool is_embree = name.rfind("embree", 0) == 0;
        for (std::size_t i = 0; i < bad_rays.size(); ++i) {
            SCOPED_TRACE(name + ", bad ray " + std::to_string(i));
            try {
                const Hit hit = accel->intersect(bad_rays[i]);
                const bool is_occluded = accel->occluded(bad_rays[i]);
                EXPECT_FALSE(hit.is_hit());
                EXPECT_FALSE(is_occluded);
            } catch (const Error& error) {
                EXPECT_TRUE(is_embree)
                    << "the project's structures answer every ray: " << error.what();
            }
        }
        // tnear = -inf is a well-defined segment (the whole line): the project's structures
        // report the hit as usual; Embree rejects a negative tnear.
        const Ray whole_line{{0, 0, 5}, -kInf, {0, 0, -1}, kInf};
        if (is_embree) {
            EXPECT_THROW((void)accel->intersect(whole_line), Error) << name;
        } else {
            EXPECT_EQ(accel->intersect(whole_line).t, 5.0f) << name;
        }
    }
}

TEST(BadInputCli, BadRayFilesExitWithOneAndNameTheLine) {
    const fs::path dir = scratch_dir();
    struct BadRays {
        std::string text;
        std::string phrase;
    };
    const std::vector<BadRays> cases = {
        // Each rule has its library test in ray_file_test.cpp; these show that the command
        // passes the message on (file, line, problem) and exits with 1.
        {"0 0 5 nan 0 -1 0 inf\n", "line 2: dx is NaN"},
        {"0 0 5 0 0 0 0 inf\n", "line 2: direction is zero"},
        {"0 0 5 0 0 -1 -1e-30 inf\n", "line 2: tnear -1e-30 is negative"},
        {"0 0 5 0 0 -1 0 inf\n0 0\x01 5 0 0 -1 0 inf\n", "line 3: oy"},
    };
    const std::string scene = tiny_scene();
    for (std::size_t i = 0; i < cases.size(); ++i) {
        const fs::path rays = dir / ("rays_" + std::to_string(i) + ".txt");
        test::write_text_file(rays, "# a comment\n" + cases[i].text);
        expect_clean_failure({"trace", scene, rays.string()}, {rays.string(), cases[i].phrase});
    }
    expect_clean_failure({"trace", scene, (dir / "no_such_rays.txt").string()},
                         {"no_such_rays.txt"});
}

TEST(BadInputCli, ReversedSegmentIsAMissInTheHitFile) {
    const fs::path dir = scratch_dir();
    // The tiny scene's triangle (0,0,0) (1,0,0) (0,1,0): the first ray hits it at t = 10,
    // the same ray with tnear 30 > tfar 20 must miss.
    test::write_text_file(dir / "rays.txt", "0.2 0.2 -10 0 0 1 0 inf\n0.2 0.2 -10 0 0 1 30 20\n");
    const std::string scene = tiny_scene();
    for (const char* accel : {"embree-flat", "rebraid"}) {
        const CommandResult result =
            run_rebraid({"trace", scene, (dir / "rays.txt").string(), "--accel", accel});
        ASSERT_EQ(result.exit_code, 0) << accel << ": " << result.err;
        std::istringstream lines(result.out);
        double t = 0.0;
        long instance_id = -1, prim_id = -1;
        lines >> t >> instance_id >> prim_id;
        EXPECT_NEAR(t, 10.0, 1e-5) << accel;
        EXPECT_EQ(instance_id, 0) << accel;
        EXPECT_EQ(prim_id, 0) << accel;
        std::string second;
        lines >> std::ws;
        std::getline(lines, second);
        EXPECT_EQ(second, "inf -1 -1") << accel;
    }
}

TEST(BadInputCli, OutOfRangeSettingsExitWithOne) {
    const std::string scene = tiny_scene();
    expect_clean_failure({"stats", scene, "--budget-factor", "1e9"},
                         {"--budget-factor: 1e9 is out of range: it must be from 0 to 1e+06"});
    expect_clean_failure({"stats", scene, "--budget-factor", "nan"},
                         {"--budget-factor: 'nan' is not a number"});
    // Ranges the command line itself checks are CLI11 parse errors: exit code 1 too, and a
    // message naming the option.
    const CommandResult negative = run_rebraid({"stats", scene, "--open-threshold", "-1"});
    EXPECT_EQ(negative.exit_code, 1);
    EXPECT_NE(negative.err.find("--open-threshold"), std::string::npos) << negative.err;
    EXPECT_EQ(run_rebraid({"stats", scene, "--threads", "many"}).exit_code, 1);
    EXPECT_EQ(run_rebraid({"--help"}).exit_code, 0);
}

}  // namespace
}  // namespace rebraid
