// `rebraid render` end to end: the files it writes, re-opened with OpenImageIO.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli_runner.h"

namespace {

namespace fs = std::filesystem;
namespace test = rebraid::test;
using test::CommandResult;

fs::path scratch_dir() {
    return test::test_scratch_dir("render_command_test", true);
}

struct ImageFile {
    std::string format;  ///< OpenImageIO's format name ("png", "openexr")
    int width = 0;
    int height = 0;
    int channels = 0;
    OIIO::TypeDesc pixel_type;
    std::vector<float> pixels;
};

ImageFile open_image(const fs::path& path) {
    ImageFile file;
    auto input = OIIO::ImageInput::open(path.string());
    if (!input) {
        ADD_FAILURE() << "OpenImageIO cannot open " << path << ": " << OIIO::geterror();
        return file;
    }
    const OIIO::ImageSpec& spec = input->spec();
    file.format = input->format_name();
    file.width = spec.width;
    file.height = spec.height;
    file.channels = spec.nchannels;
    file.pixel_type = spec.format;
    file.pixels.resize(static_cast<std::size_t>(spec.width) * spec.height * spec.nchannels);
    EXPECT_TRUE(
        input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, file.pixels.data()));
    input->close();
    return file;
}

std::string shared_scene(const std::string& name) {
    return std::string(REBRAID_SHARED_SCENES) + "/" + name;
}

TEST(RenderCommand, PngAndExrHaveRequestedSizeAndFormat) {
    const fs::path dir = scratch_dir();
    const fs::path png = dir / "image.png", exr = dir / "image.exr";
    for (const fs::path& path : {png, exr}) {
        const CommandResult result =
            test::run_rebraid_in(dir, {"render", "--mode", "path", "--spp", "1", "--width", "40",
                                       "--height", "30", "-o", path.string()});
        ASSERT_EQ(result.exit_code, 0) << result.err;
    }
    const ImageFile png_file = open_image(png);
    EXPECT_EQ(png_file.format, "png");
    EXPECT_EQ(png_file.width, 40);
    EXPECT_EQ(png_file.height, 30);
    EXPECT_EQ(png_file.channels, 3);
    EXPECT_EQ(png_file.pixel_type, OIIO::TypeDesc::UINT8);

    const ImageFile exr_file = open_image(exr);
    EXPECT_EQ(exr_file.format, "openexr");
    EXPECT_EQ(exr_file.width, 40);
    EXPECT_EQ(exr_file.height, 30);
    EXPECT_EQ(exr_file.channels, 3);
    EXPECT_EQ(exr_file.pixel_type, OIIO::TypeDesc::HALF);
    // The EXR holds linear values, the PNG their sRGB encoding: a mid-grey linear value is
    // brighter in the PNG.
    ASSERT_EQ(png_file.pixels.size(), exr_file.pixels.size());
    double png_sum = 0.0, exr_sum = 0.0;
    for (std::size_t i = 0; i < png_file.pixels.size(); ++i) {
        png_sum += png_file.pixels[i];
        exr_sum += std::min(1.0f, exr_file.pixels[i]);
    }
    EXPECT_GT(png_sum, exr_sum * 1.1);
}

TEST(RenderCommand, CompareWritesHeatmapsSideBySideWithTotals) {
    const fs::path dir = scratch_dir();
    const fs::path image = dir / "compare.png";
    const CommandResult result =
        test::run_rebraid_in(dir, {"render", "--compare", "twolevel,rebraid", "--width", "48",
                                   "--height", "32", "-o", image.string()});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const ImageFile file = open_image(image);
    EXPECT_EQ(file.format, "png");
    EXPECT_EQ(file.width, 2 * 48);
    EXPECT_EQ(file.height, 32);
    // One totals line per structure.
    EXPECT_NE(result.out.find("twolevel: "), std::string::npos) << result.out;
    EXPECT_NE(result.out.find("rebraid: "), std::string::npos) << result.out;
    EXPECT_NE(result.out.find("nodes visited"), std::string::npos) << result.out;
    EXPECT_NE(result.out.find("Mrays/s"), std::string::npos) << result.out;
}

TEST(RenderCommand, FramesAreNumberedPngsOfRequestedSize) {
    const fs::path dir = scratch_dir();
    const CommandResult result =
        test::run_rebraid_in(dir, {"render", shared_scene("motion_capture_rom.glb"), "--mode",
                                   "normals", "--frames", "3", "--time-step", "0.5", "--width",
                                   "32", "--height", "24", "-o", (dir / "anim.png").string()});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    std::vector<ImageFile> frames;
    for (const char* name : {"anim_0000.png", "anim_0001.png", "anim_0002.png"}) {
        frames.push_back(open_image(dir / name));
        EXPECT_EQ(frames.back().format, "png") << name;
        EXPECT_EQ(frames.back().width, 32) << name;
        EXPECT_EQ(frames.back().height, 24) << name;
    }
    EXPECT_FALSE(fs::exists(dir / "anim.png"));
    EXPECT_FALSE(fs::exists(dir / "anim_0003.png"));
    // The figure moves between frames.
    EXPECT_NE(frames[0].pixels, frames[2].pixels);
}

}  // namespace
