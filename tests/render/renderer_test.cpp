// The viewer in process: the same image through every structure and on any thread count,
// and the heatmap's work totals.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "embree_glue/reference/embree_reference.h"
#include "rebraid/generators/default_scene.h"
#include "rebraid/io/gltf_camera.h"
#include "rebraid/io/gltf_scene.h"
#include "rebraid/rebraiding/rebraid_accel.h"
#include "rebraid/rebraiding/rebraid_builder.h"
#include "rebraid/render/camera_setup.h"
#include "rebraid/render/colour.h"
#include "rebraid/render/heatmap.h"
#include "rebraid/render/renderer.h"
#include "rebraid/render/surface_materials.h"
#include "rebraid/top_level/flat_accel.h"
#include "rebraid/top_level/instanced_accel.h"
#include "support/test_scenes.h"

namespace rebraid::viewer {
namespace {

/// A scene with what the viewer reads from its file.
struct ViewerScene {
    std::string name;
    Scene scene;
    std::vector<GltfCamera> cameras;
    SurfaceMaterials materials;
};

ViewerScene default_viewer_scene() {
    return {"default scene", make_default_scene(), {}, {}};
}

ViewerScene shared_viewer_scene(const std::string& file) {
    const std::string path = std::string(REBRAID_SHARED_SCENES) + "/" + file;
    GltfLoadResult loaded = load_gltf_scene_with_report(path, {.keep_model = true});
    std::vector<std::string> warnings;
    SurfaceMaterials materials = SurfaceMaterials::from_gltf(loaded, path, warnings);
    EXPECT_TRUE(warnings.empty()) << file << ": " << warnings.front();
    return {file, std::move(loaded.scene), read_gltf_cameras(loaded), std::move(materials)};
}

/// The image as a PNG would store it: 8-bit sRGB codes.
std::vector<int> png_codes(const Image& image) {
    std::vector<int> codes;
    codes.reserve(image.rgb.size());
    for (float value : image.rgb)
        codes.push_back(static_cast<int>(std::lround(linear_to_srgb(value) * 255.0f)));
    return codes;
}

/// Pixels whose 8-bit codes differ by more than 1 in some channel.
int count_pixels_beyond_one_code(const Image& a, const Image& b) {
    const std::vector<int> codes_a = png_codes(a), codes_b = png_codes(b);
    int count = 0;
    for (std::size_t pixel = 0; pixel + 2 < codes_a.size(); pixel += 3) {
        bool differs = false;
        for (std::size_t c = 0; c < 3; ++c)
            differs = differs || std::abs(codes_a[pixel + c] - codes_b[pixel + c]) > 1;
        count += differs;
    }
    return count;
}

RenderSettings small_path_settings() {
    RenderSettings settings;
    settings.width = 48;
    settings.height = 32;
    settings.mode = ShadingMode::path;
    settings.samples_per_pixel = 2;
    settings.max_bounces = 3;
    return settings;
}

Camera camera_for(const ViewerScene& viewer_scene, const RenderSettings& settings) {
    return choose_camera(viewer_scene.scene, viewer_scene.cameras, {},
                         static_cast<float>(settings.width) / static_cast<float>(settings.height))
        .camera;
}

// fzk_haus is not among the scenes: its walls and windows overlap in the same planes, and
// there the closest hit is a tie that any structure may win (README, hit file contract).
TEST(ViewerRender, SameImageThroughEveryStructure) {
    std::vector<ViewerScene> scenes;
    scenes.push_back(default_viewer_scene());
    scenes.push_back(shared_viewer_scene("two_cylinder_engine.glb"));
    scenes.push_back(shared_viewer_scene("cg57_cruiser.glb"));
    const RenderSettings settings = small_path_settings();
    for (const ViewerScene& viewer_scene : scenes) {
        const Scene& scene = viewer_scene.scene;
        const Camera camera = camera_for(viewer_scene, settings);
        std::vector<std::pair<std::string, std::unique_ptr<Accel>>> accels;
        // Embree's robust mode and the watertight triangle test: neither lets a ray slip
        // between two triangles, so the pictures agree pixel for pixel. (Without, each may
        // leak through a different edge: one pixel of two_cylinder_engine differs.)
        accels.emplace_back("embree-flat", std::make_unique<glue::EmbreeFlatAccel>(scene));
        auto flat = std::make_unique<FlatAccel>(scene);
        flat->set_triangle_test(TriangleTest::watertight);
        accels.emplace_back("flat", std::move(flat));
        auto two_level = std::make_unique<InstancedAccel>(build_two_level_accel(scene));
        two_level->set_triangle_test(TriangleTest::watertight);
        accels.emplace_back("twolevel", std::move(two_level));
        auto rebraid = std::make_unique<InstancedAccel>(build_rebraid_accel(scene));
        rebraid->set_triangle_test(TriangleTest::watertight);
        accels.emplace_back("rebraid", std::move(rebraid));

        const Image reference =
            render_image(scene, *accels[0].second, camera, viewer_scene.materials, settings).image;
        // The picture must show something, or the comparison proves little.
        const std::vector<int> codes = png_codes(reference);
        EXPECT_GT(std::set<int>(codes.begin(), codes.end()).size(), 20u) << viewer_scene.name;
        for (std::size_t i = 1; i < accels.size(); ++i) {
            const RenderResult result =
                render_image(scene, *accels[i].second, camera, viewer_scene.materials, settings);
            ASSERT_TRUE(result.is_complete());
            EXPECT_EQ(count_pixels_beyond_one_code(reference, result.image), 0)
                << viewer_scene.name << ": " << accels[i].first << " against embree-flat";
        }
    }
}

TEST(ViewerRender, SameImageOnOneAndTwoThreads) {
    const ViewerScene viewer_scene = default_viewer_scene();
    const Scene& scene = viewer_scene.scene;
    const InstancedAccel accel = build_rebraid_accel(scene);
    for (ShadingMode mode : {ShadingMode::ao, ShadingMode::path}) {
        RenderSettings settings = small_path_settings();
        settings.mode = mode;
        const Camera camera = camera_for(viewer_scene, settings);
        std::vector<Image> images;
        for (int threads : {1, 2}) {
            tbb::task_arena arena(threads);
            arena.execute([&] {
                images.push_back(
                    render_image(scene, accel, camera, viewer_scene.materials, settings).image);
            });
        }
        EXPECT_EQ(images[0].rgb, images[1].rgb) << shading_mode_name(mode);
    }
}

TEST(ViewerHeatmap, SameCountersOnOneAndTwoThreads) {
    const Scene scene = make_default_scene();
    const InstancedAccel accel = build_two_level_accel(scene);
    const HeatmapSettings settings{.width = 40, .height = 30, .timing_run_count = 0};
    const Camera camera = frame_scene(scene, 4.0f / 3.0f);
    std::vector<HeatmapPanel> panels;
    for (int threads : {1, 2}) {
        tbb::task_arena arena(threads);
        arena.execute(
            [&] { panels.push_back(trace_heatmap("twolevel", accel, camera, settings)); });
    }
    ASSERT_EQ(panels[0].per_pixel.size(), panels[1].per_pixel.size());
    for (std::size_t p = 0; p < panels[0].per_pixel.size(); ++p) {
        ASSERT_EQ(panels[0].per_pixel[p].nodes_visited, panels[1].per_pixel[p].nodes_visited) << p;
        ASSERT_EQ(panels[0].per_pixel[p].triangles_tested, panels[1].per_pixel[p].triangles_tested)
            << p;
    }
}

TEST(ViewerHeatmap, RebraidVisitsNoMoreNodesThanTwoLevelOnOverlapScene) {
    const Scene scene = test::make_overlap_scene(200, 7);
    const InstancedAccel two_level = build_two_level_accel(scene);
    const InstancedAccel rebraid = build_rebraid_accel(scene);
    const HeatmapSettings settings{.width = 64, .height = 48, .timing_run_count = 0};
    const Camera camera = frame_scene(scene, 4.0f / 3.0f);
    const HeatmapPanel two_level_panel = trace_heatmap("twolevel", two_level, camera, settings);
    const HeatmapPanel rebraid_panel = trace_heatmap("rebraid", rebraid, camera, settings);
    // Every primary ray was traced and did some work.
    EXPECT_EQ(two_level_panel.ray_count, 64u * 48u);
    EXPECT_GT(two_level_panel.totals.nodes_visited, two_level_panel.ray_count);
    EXPECT_LE(rebraid_panel.totals.nodes_visited, two_level_panel.totals.nodes_visited)
        << describe_heatmap_totals(two_level_panel) << "\n"
        << describe_heatmap_totals(rebraid_panel);
    // The drawn comparison puts the two panels side by side.
    const std::vector<HeatmapPanel> panels{two_level_panel, rebraid_panel};
    const Image image = draw_heatmaps(panels, settings);
    EXPECT_EQ(image.width, 2 * 64);
    EXPECT_EQ(image.height, 48);
}

}  // namespace
}  // namespace rebraid::viewer
