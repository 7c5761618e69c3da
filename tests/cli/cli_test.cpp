// End-to-end tests of the `rebraid` command: run the built binary, check files and output.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "rebraid/generators/default_scene.h"
#include "support/cli_runner.h"

namespace {

namespace fs = std::filesystem;
namespace test = rebraid::test;
using test::CommandResult;

fs::path scratch_dir() {
    return test::test_scratch_dir("cli_test");
}

CommandResult run_rebraid(std::initializer_list<std::string> arguments) {
    return test::run_rebraid_in(scratch_dir(), arguments);
}

std::vector<std::string> split_lines(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
}

std::vector<std::string> split_fields(const std::string& line) {
    std::vector<std::string> fields;
    std::istringstream in(line);
    for (std::string field; in >> field;) fields.push_back(field);
    return fields;
}

std::string base64(const std::vector<unsigned char>& bytes) {
    static constexpr char kAlphabet[] =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string text;
    for (std::size_t i = 0; i < bytes.size(); i += 3) {
        const std::size_t available = std::min<std::size_t>(3, bytes.size() - i);
        std::uint32_t group = static_cast<std::uint32_t>(bytes[i]) << 16u;
        if (available > 1) group |= static_cast<std::uint32_t>(bytes[i + 1]) << 8u;
        if (available > 2) group |= bytes[i + 2];
        for (std::size_t k = 0; k < 4; ++k)
            text += k <= available ? kAlphabet[(group >> (18u - 6u * k)) & 63u] : '=';
    }
    return text;
}

template <class T>
void append_bytes(std::vector<unsigned char>& bytes, const T& value) {
    unsigned char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    bytes.insert(bytes.end(), raw, raw + sizeof(T));
}

/// Writes a glTF with one mesh, the unit quad in the z = 0 plane (corners 0:(0,0) 1:(1,0)
/// 2:(1,1) 3:(0,1); triangle 0 = 0,1,2 below the diagonal x = y, triangle 1 = 0,2,3 above),
/// instanced twice: instance 0 at z = 0, instance 1 at z = -2.
fs::path write_two_quads_gltf(const fs::path& dir) {
    std::vector<unsigned char> buffer;
    const float positions[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    for (const auto& p : positions)
        for (float c : p) append_bytes(buffer, c);
    const std::uint16_t indices[6] = {0, 1, 2, 0, 2, 3};
    for (std::uint16_t i : indices) append_bytes(buffer, i);

    const nlohmann::json gltf = {
        {"asset", {{"version", "2.0"}}},
        {"scene", 0},
        {"scenes", {{{"nodes", {0, 1}}}}},
        {"nodes", {{{"mesh", 0}}, {{"mesh", 0}, {"translation", {0.0, 0.0, -2.0}}}}},
        {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
        {"accessors",
         {{{"bufferView", 0},
           {"componentType", 5126},
           {"count", 4},
           {"type", "VEC3"},
           {"min", {0.0, 0.0, 0.0}},
           {"max", {1.0, 1.0, 0.0}}},
          {{"bufferView", 1}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}}}},
        {"bufferViews",
         {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 48}},
          {{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 12}}}},
        {"buffers",
         {{{"byteLength", buffer.size()},
           {"uri", "data:application/octet-stream;base64," + base64(buffer)}}}},
    };
    const fs::path path = dir / "two_quads.gltf";
    test::write_text_file(path, gltf.dump(2));
    return path;
}

struct ParsedHit {
    double t = 0.0;
    long instance_id = 0;
    long prim_id = 0;
};

/// Parses a hit line, failing the test when it is not `t instID primID`.
ParsedHit parse_hit_line(const std::string& line) {
    const std::vector<std::string> fields = split_fields(line);
    EXPECT_EQ(fields.size(), 3u) << "hit line '" << line << "'";
    ParsedHit hit;
    if (fields.size() != 3) return hit;
    hit.t = std::stod(fields[0]);
    hit.instance_id = std::stol(fields[1]);
    hit.prim_id = std::stol(fields[2]);
    return hit;
}

TEST(CliTrace, WritesOneHitLinePerRayInInputOrder) {
    const fs::path dir = scratch_dir();
    const fs::path scene = write_two_quads_gltf(dir);
    const fs::path rays = dir / "rays.txt";
    test::write_text_file(rays,
                          "# ox oy oz dx dy dz tnear tfar\n"
                          "0.75 0.25 5  0 0 -1  0 inf\n"  // below the diagonal: triangle 0, t = 5
                          "0.25 0.75 5  0 0 -2  0 inf\n"  // above it: triangle 1; t in units of dir
                          "\n"
                          "0.25 0.75 5  0 0 -1  0 4\n"    // tfar ends before the quad
                          "0.75 0.25 5  0 0 -1  6 inf\n"  // tnear skips instance 0, hits instance 1
                          "0.5 0.5 5  0 0 1  0 inf\n"     // pointing away
                          "3 3 5  0 0 -1  0 inf\n");      // beside the quads

    const CommandResult result = run_rebraid({"trace", scene.string(), rays.string()});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const std::vector<std::string> lines = split_lines(result.out);
    ASSERT_EQ(lines.size(), 6u) << result.out;

    const ParsedHit first = parse_hit_line(lines[0]);
    EXPECT_NEAR(first.t, 5.0, 1e-5);
    EXPECT_EQ(first.instance_id, 0);
    EXPECT_EQ(first.prim_id, 0);
    const ParsedHit second = parse_hit_line(lines[1]);
    EXPECT_NEAR(second.t, 2.5, 1e-5);
    EXPECT_EQ(second.instance_id, 0);
    EXPECT_EQ(second.prim_id, 1);
    EXPECT_EQ(split_fields(lines[2]), (std::vector<std::string>{"inf", "-1", "-1"}));
    const ParsedHit fourth = parse_hit_line(lines[3]);
    EXPECT_NEAR(fourth.t, 7.0, 1e-5);
    EXPECT_EQ(fourth.instance_id, 1);
    EXPECT_EQ(fourth.prim_id, 0);
    EXPECT_EQ(split_fields(lines[4]), (std::vector<std::string>{"inf", "-1", "-1"}));
    EXPECT_EQ(split_fields(lines[5]), (std::vector<std::string>{"inf", "-1", "-1"}));

    // -o writes the same lines to a file and nothing to stdout.
    const fs::path hits = dir / "nested" / "hits.txt";
    const CommandResult to_file =
        run_rebraid({"trace", scene.string(), rays.string(), "-o", hits.string()});
    ASSERT_EQ(to_file.exit_code, 0) << to_file.err;
    EXPECT_TRUE(to_file.out.empty());
    EXPECT_EQ(test::read_text_file(hits), result.out);
}

TEST(CliTrace, EmbreeFlatAndInstancedAgreeOnRandomRaysInDefaultScene) {
    const fs::path dir = scratch_dir();
    const fs::path rays = dir / "rays.txt";
    ASSERT_EQ(
        run_rebraid({"rays", "--count", "2000", "--seed", "7", "-o", rays.string()}).exit_code, 0);
    // One positional: the ray file, on the default scene.
    const CommandResult flat = run_rebraid({"trace", rays.string(), "--accel", "embree-flat"});
    const CommandResult instanced =
        run_rebraid({"trace", rays.string(), "--accel", "embree-instanced", "--threads", "1"});
    ASSERT_EQ(flat.exit_code, 0) << flat.err;
    ASSERT_EQ(instanced.exit_code, 0) << instanced.err;

    const std::vector<std::string> flat_lines = split_lines(flat.out);
    const std::vector<std::string> instanced_lines = split_lines(instanced.out);
    ASSERT_EQ(flat_lines.size(), 2000u);
    ASSERT_EQ(instanced_lines.size(), 2000u);
    int hit_count = 0;
    for (std::size_t i = 0; i < flat_lines.size(); ++i) {
        const ParsedHit a = parse_hit_line(flat_lines[i]);
        const ParsedHit b = parse_hit_line(instanced_lines[i]);
        ASSERT_EQ(a.instance_id, b.instance_id) << "ray " << i;
        ASSERT_EQ(a.prim_id, b.prim_id) << "ray " << i;
        if (std::isinf(a.t)) {
            EXPECT_TRUE(std::isinf(b.t)) << "ray " << i;
        } else {
            ++hit_count;
            // Instanced tracing transforms the ray into object space, so t differs in the
            // last bits (the printed 9 digits show it); the project's tolerance is 1e-4.
            EXPECT_NEAR(a.t, b.t, 1e-4 * std::max(1.0, std::fabs(a.t))) << "ray " << i;
        }
    }
    // Random rays in and around the scene must hit something, and not everything.
    EXPECT_GT(hit_count, 0);
    EXPECT_LT(hit_count, 2000);
}

TEST(CliStats, JsonHasCountsOfTheScene) {
    const fs::path dir = scratch_dir();
    const fs::path scene = write_two_quads_gltf(dir);
    const CommandResult result = run_rebraid({"stats", scene.string(), "--json"});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const nlohmann::json json = nlohmann::json::parse(result.out);  // throws on extra text
    ASSERT_TRUE(json.is_object());
    EXPECT_EQ(json.at("triangles").get<std::uint64_t>(), 4u);
    EXPECT_EQ(json.at("instances").get<std::uint64_t>(), 2u);
    EXPECT_EQ(json.at("meshes").get<std::uint64_t>(), 1u);
    EXPECT_GE(json.at("build_ms").get<double>(), 0.0);
}

TEST(CliStats, JsonMatchesDefaultSceneForBothEmbreeStructures) {
    const rebraid::Scene scene = rebraid::make_default_scene();
    for (const char* accel : {"embree-flat", "embree-instanced"}) {
        const CommandResult result = run_rebraid({"stats", "--json", "--accel", accel});
        ASSERT_EQ(result.exit_code, 0) << result.err;
        const nlohmann::json json = nlohmann::json::parse(result.out);
        EXPECT_EQ(json.at("triangles").get<std::uint64_t>(), scene.instanced_triangle_count())
            << accel;
        EXPECT_EQ(json.at("instances").get<std::uint64_t>(), scene.instances.size()) << accel;
        EXPECT_EQ(json.at("meshes").get<std::uint64_t>(), scene.meshes.size()) << accel;
        EXPECT_GT(json.at("build_ms").get<double>(), 0.0) << accel;
    }
}

TEST(CliStats, DefaultNamesTheBuiltInSceneAsAnOmittedSceneDoes) {
    const CommandResult omitted = run_rebraid({"stats", "--json", "--accel", "twolevel"});
    const CommandResult named = run_rebraid({"stats", "default", "--json", "--accel", "twolevel"});
    ASSERT_EQ(omitted.exit_code, 0) << omitted.err;
    ASSERT_EQ(named.exit_code, 0) << named.err;
    const nlohmann::json a = nlohmann::json::parse(omitted.out);
    const nlohmann::json b = nlohmann::json::parse(named.out);
    EXPECT_EQ(a.at("structure_hash"), b.at("structure_hash"));
    EXPECT_EQ(b.at("instances").get<std::uint64_t>(),
              rebraid::make_default_scene().instances.size());
}

TEST(CliStats, JsonNamesTheObjectBuilderOfAVariant) {
    // A variant's object-builder key overrides --object-builder: the JSON must name the
    // builder that built the structure, and the structure must be the one that builder makes.
    const fs::path scene = write_two_quads_gltf(scratch_dir());
    const CommandResult variant = run_rebraid(
        {"stats", scene.string(), "--json", "--accel", "twolevel:object-builder=embree-medium"});
    const CommandResult option = run_rebraid({"stats", scene.string(), "--json", "--accel",
                                              "twolevel", "--object-builder", "embree-medium"});
    ASSERT_EQ(variant.exit_code, 0) << variant.err;
    ASSERT_EQ(option.exit_code, 0) << option.err;
    const nlohmann::json a = nlohmann::json::parse(variant.out);
    const nlohmann::json b = nlohmann::json::parse(option.out);
    EXPECT_EQ(a.at("object_builder"), "embree-medium");
    EXPECT_EQ(b.at("object_builder"), "embree-medium");
    EXPECT_EQ(a.at("structure_hash"), b.at("structure_hash"));
}

TEST(CliStats, TextNamesEveryCount) {
    const fs::path scene = write_two_quads_gltf(scratch_dir());
    const CommandResult result = run_rebraid({"stats", scene.string()});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    for (const char* key : {"triangles", "instances", "meshes", "build_ms"})
        EXPECT_NE(result.out.find(key), std::string::npos) << key << " in\n" << result.out;
}

struct LoadedImage {
    int width = 0;
    int height = 0;
    int channels = 0;
    std::vector<unsigned char> pixels;
};

LoadedImage read_image(const fs::path& path) {
    LoadedImage image;
    auto input = OIIO::ImageInput::open(path.string());
    if (!input) {
        ADD_FAILURE() << "cannot open " << path << ": " << OIIO::geterror();
        return image;
    }
    const OIIO::ImageSpec& spec = input->spec();
    image.width = spec.width;
    image.height = spec.height;
    image.channels = spec.nchannels;
    image.pixels.resize(static_cast<std::size_t>(spec.width) * spec.height * spec.nchannels);
    EXPECT_TRUE(
        input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, image.pixels.data()));
    input->close();
    return image;
}

TEST(CliRender, WritesPngOfRequestedSizeThatIsNotOneColour) {
    const fs::path dir = scratch_dir();
    const fs::path image_path = dir / "made" / "by" / "render.png";  // folders get created
    fs::remove_all(dir / "made");
    const CommandResult result = run_rebraid(
        {"render", "-o", image_path.string(), "--width", "64", "--height", "48", "--spp", "2"});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const LoadedImage image = read_image(image_path);
    EXPECT_EQ(image.width, 64);
    EXPECT_EQ(image.height, 48);
    ASSERT_GE(image.channels, 3);
    bool has_second_colour = false;
    for (std::size_t i = image.channels; i < image.pixels.size() && !has_second_colour; ++i)
        has_second_colour = image.pixels[i] != image.pixels[i % image.channels];
    EXPECT_TRUE(has_second_colour) << "every pixel has the colour of the first";
}

TEST(CliRender, SameImageOnOneAndTwoThreads) {
    const fs::path dir = scratch_dir();
    const fs::path scene = write_two_quads_gltf(dir);
    const fs::path one = dir / "one_thread.png";
    const fs::path two = dir / "two_threads.png";
    for (const auto& [path, threads] : {std::pair{one, "1"}, std::pair{two, "2"}}) {
        const CommandResult result =
            run_rebraid({"render", scene.string(), "-o", path.string(), "--width", "40", "--height",
                         "30", "--spp", "3", "--threads", threads});
        ASSERT_EQ(result.exit_code, 0) << result.err;
    }
    const LoadedImage a = read_image(one);
    const LoadedImage b = read_image(two);
    EXPECT_EQ(a.width, 40);
    EXPECT_EQ(a.pixels, b.pixels);
}

TEST(CliRays, SameSeedGivesSameFileWithCountLines) {
    const fs::path dir = scratch_dir();
    const fs::path scene = write_two_quads_gltf(dir);
    const fs::path first = dir / "first.txt";
    const fs::path second = dir / "second.txt";
    const fs::path other_seed = dir / "other_seed.txt";
    for (const auto& [path, seed] :
         {std::pair{first, "11"}, std::pair{second, "11"}, std::pair{other_seed, "12"}}) {
        const CommandResult result = run_rebraid(
            {"rays", scene.string(), "--count", "300", "--seed", seed, "-o", path.string()});
        ASSERT_EQ(result.exit_code, 0) << result.err;
    }
    const std::string text = test::read_text_file(first);
    EXPECT_EQ(text, test::read_text_file(second));
    EXPECT_NE(text, test::read_text_file(other_seed));
    const std::vector<std::string> lines = split_lines(text);
    ASSERT_EQ(lines.size(), 300u);
    for (const std::string& line : lines) EXPECT_EQ(split_fields(line).size(), 8u) << line;

    // Without -o the same rays go to stdout.
    const CommandResult to_stdout =
        run_rebraid({"rays", scene.string(), "--count", "300", "--seed", "11"});
    ASSERT_EQ(to_stdout.exit_code, 0) << to_stdout.err;
    EXPECT_EQ(to_stdout.out, text);
}

TEST(CliErrors, UnknownAccelNameListsValidNames) {
    const CommandResult result = run_rebraid({"stats", "--accel", "no-such-bvh"});
    EXPECT_EQ(result.exit_code, 1);
    EXPECT_EQ(result.err.rfind("rebraid: ", 0), 0u) << result.err;
    EXPECT_NE(result.err.find("unknown accel 'no-such-bvh'"), std::string::npos) << result.err;
    EXPECT_NE(result.err.find("embree-flat"), std::string::npos) << result.err;
    EXPECT_NE(result.err.find("embree-instanced"), std::string::npos) << result.err;
}

TEST(CliErrors, MissingSceneFileIsNamed) {
    const fs::path missing = scratch_dir() / "no_such_scene.glb";
    const CommandResult result = run_rebraid({"stats", missing.string()});
    EXPECT_EQ(result.exit_code, 1);
    EXPECT_NE(result.err.find("does not exist"), std::string::npos) << result.err;
    EXPECT_NE(result.err.find(missing.string()), std::string::npos) << result.err;
}

TEST(CliErrors, BadRayLineNamesFileAndLine) {
    const fs::path dir = scratch_dir();
    const fs::path scene = write_two_quads_gltf(dir);
    const fs::path rays = dir / "bad_rays.txt";
    test::write_text_file(rays, "0 0 5 0 0 -1 0 inf\n0 0 5 0 zero -1 0 inf\n");
    const CommandResult result = run_rebraid({"trace", scene.string(), rays.string()});
    EXPECT_EQ(result.exit_code, 1);
    EXPECT_EQ(result.err.rfind("rebraid: ", 0), 0u) << result.err;
    EXPECT_NE(result.err.find(rays.string()), std::string::npos) << result.err;
    EXPECT_NE(result.err.find("line 2"), std::string::npos) << result.err;
}

TEST(CliErrors, ParseErrorsExitWithOne) {
    // Exactly 1, as the README promises: not a crash, a sanitizer's exit code or an abort.
    EXPECT_EQ(run_rebraid({"trace"}).exit_code, 1);                      // RAYS missing
    EXPECT_EQ(run_rebraid({"trace", "a", "b", "c"}).exit_code, 1);       // one too many
    EXPECT_EQ(run_rebraid({"rays"}).exit_code, 1);                       // --count missing
    EXPECT_EQ(run_rebraid({"render", "--threads", "-2"}).exit_code, 1);  // negative threads
    EXPECT_EQ(run_rebraid({"no-such-command"}).exit_code, 1);
}

TEST(CliHelp, EverySubcommandDocumentsItsOptions) {
    for (const char* command : {"trace", "stats", "render", "rays"}) {
        const CommandResult result = run_rebraid({command, "--help"});
        EXPECT_EQ(result.exit_code, 0) << command;
        EXPECT_NE(result.out.find("--threads"), std::string::npos) << command << result.out;
    }
    EXPECT_NE(run_rebraid({"trace", "--help"}).out.find("--accel"), std::string::npos);
}

}  // namespace
