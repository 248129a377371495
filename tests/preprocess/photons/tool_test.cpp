// End-to-end tests of the prt-photons tool: --help, sections written into the pools in place,
// removed when a pool gets no deposit, one-line errors naming the file, no partial output.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "gi_test_util.h"
#include "prt/runtime/gi_pool.h"
#include "runtime/surface_fixtures.h"
#include "runtime/tool_run.h"

using namespace prt;

namespace {

void write_text(const std::filesystem::path& p, const std::string& text) {
    std::ofstream(p) << text;
}

const char* k_scene = R"({
  "lights": [{"type": "point", "position": [0, 2, 0]}],
  "materials": [{"name": "floor"},
                {"name": "glass", "refractive_index": 1.5, "transmissivity": 0.9, "reflectivity": 0.1,
                 "diffuse_reflectance": 0}],
  "models": [{"name": "floor", "pool": "floor.pool", "material": "floor"},
             {"name": "ball", "pool": "ball.pool", "material": "glass"}]
})";

}  // namespace

TEST(PhotonsTool, HelpDocumentsDefaults) {
    const auto dir = test::fresh_dir("photons_help");
    const test::ToolRun r = test::run_tool("prt-photons", "--help", dir);
    EXPECT_EQ(r.code, 0);
    for (const char* opt : {"--face-res", "--per-pixel", "--max-bounces", "--caustic-levels", "--backend",
                            "--threads", "--quiet", "--gather-radius"})
        EXPECT_NE(r.out.find(opt), std::string::npos) << opt;
    EXPECT_NE(r.out.find("512"), std::string::npos);
}

TEST(PhotonsTool, WritesCausticsIntoThePoolsInPlace) {
    const auto dir = test::fresh_dir("photons_tool");
    test::write_model_pool(
        test::make_model(test::rect_points({-2, 0, -2}, {4, 0, 0}, {0, 0, 4}, {0, 1, 0}, 150), {0, 0, 0}),
        dir / "floor.pool");
    test::write_model_pool(test::make_model(test::sphere_points({0, 0.8, 0}, 0.4, 20000), {0, 0.8, 0}),
                           dir / "ball.pool");
    write_text(dir / "scene.json", k_scene);
    test::ToolRun r = test::run_tool(
        "prt-photons", (dir / "scene.json").string() + " --face-res 96 --per-pixel 2 --backend cpu --quiet",
        dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(r.err.empty()) << r.err;
    {
        const pool::PoolFile floor = pool::PoolFile::open(dir / "floor.pool");
        const core::CausticView v = rt::load_caustic_view(floor);
        EXPECT_GT(v.tree.leaf_count, 0u);
        EXPECT_NE(floor.provenance_json().find("prt-photons"), std::string::npos);
        EXPECT_TRUE(floor.has(pool::SectionType::splats));  // carried over
        // The glass ball receives no deposit (no diffuse share): no caustic sections.
        EXPECT_FALSE(rt::has_caustics(pool::PoolFile::open(dir / "ball.pool")));
    }
    // Without --quiet: the phase times (trace, gather and its phases, pool writes) on stderr.
    r = test::run_tool("prt-photons",
                       (dir / "scene.json").string() + " --face-res 32 --per-pixel 1 --backend cpu", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char* phase : {"phases: load ", ", trace ", ", gather ", ", pool writes ", "; total ",
                              "leaves: bin ", "densities + leaves ", "octree "})
        EXPECT_NE(r.err.find(phase), std::string::npos) << phase << " in\n" << r.err;
    // Without the ball there are no specular paths: the old caustic sections go away.
    std::string no_ball = k_scene;
    no_ball.replace(no_ball.find(",\n             {\"name\": \"ball\""), std::string::npos, "]}");
    write_text(dir / "floor_only.json", no_ball);
    r = test::run_tool("prt-photons",
                       (dir / "floor_only.json").string() + " --face-res 32 --per-pixel 1 --quiet", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_FALSE(rt::has_caustics(pool::PoolFile::open(dir / "floor.pool")));
    for (const auto& e : std::filesystem::directory_iterator(dir))
        EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
}

TEST(PhotonsTool, APoolPlacedTwiceGetsACausticMapPerPlacement) {
    // Issue 20: one floor pool (2 x 2) and one glass-ball pool (radius 0.3, 0.6 above the floor),
    // each placed at x = -1.2 and x = +1.2, under a light at (0, 2, 0). Each ball focuses the light
    // on its floor away from the light, at local x ~ -0.51 under the left ball and +0.51 under the
    // right one (the line from the light through the ball's centre meets the floor there). Each placement's
    // map must hold its own caustic and not the other's, which one map for both would.
    const auto dir = test::fresh_dir("photons_instances");
    test::write_model_pool(
        test::make_model(test::rect_points({-1, 0, -1}, {2, 0, 0}, {0, 0, 2}, {0, 1, 0}, 100), {0, 0, 0}),
        dir / "floor.pool");
    test::write_model_pool(test::make_model(test::sphere_points({0, 0.6, 0}, 0.3, 20000), {0, 0.6, 0}),
                           dir / "ball.pool");
    write_text(dir / "scene.json", R"({
  "lights": [{"type": "point", "position": [0, 2, 0]}],
  "materials": [{"name": "floor"},
                {"name": "glass", "refractive_index": 1.5, "transmissivity": 1, "diffuse_reflectance": 0}],
  "models": [{"name": "left floor", "pool": "floor.pool", "material": "floor", "transform": {"translate": [-1.2, 0, 0]}},
             {"name": "right floor", "pool": "floor.pool", "material": "floor", "transform": {"translate": [1.2, 0, 0]}},
             {"name": "left ball", "pool": "ball.pool", "material": "glass", "transform": {"translate": [-1.2, 0, 0]}},
             {"name": "right ball", "pool": "ball.pool", "material": "glass", "transform": {"translate": [1.2, 0, 0]}}],
  "render": {"caustics": true}
})");
    const test::ToolRun r = test::run_tool(
        "prt-photons", (dir / "scene.json").string() + " --face-res 128 --per-pixel 4 --backend cpu", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("one caustic map per placement"), std::string::npos) << r.err;
    {
        const pool::PoolFile floor = pool::PoolFile::open(dir / "floor.pool");
        ASSERT_EQ(pool::validate_caustic_maps(floor).size(), 2u);
    }
    const scene::Scene sc = scene::load_scene(dir / "scene.json");
    const rt::RenderScene rs = rt::RenderScene::load(sc);
    const core::SceneView v = rs.view();
    auto caustic = [&](std::uint32_t model, float x) {
        return core::caustic_radiance(v.models[model].caustics, core::Vec3{x, 0, 0}, core::Vec3{0, 1, 0}).y;
    };
    const float spot = 1.2f * 0.6f / 1.4f;  // the caustic's centre, local frame
    float left_peak = 0, right_peak = 0, left_wrong = 0, right_wrong = 0;
    for (float dx = -0.1f; dx <= 0.1f; dx += 0.01f) {
        left_peak = std::max(left_peak, caustic(0, -spot + dx));
        left_wrong = std::max(left_wrong, caustic(0, spot + dx));
        right_peak = std::max(right_peak, caustic(1, spot + dx));
        right_wrong = std::max(right_wrong, caustic(1, -spot + dx));
    }
    EXPECT_GT(left_peak, 0.0f);
    EXPECT_GT(right_peak, 0.0f);
    EXPECT_LT(left_wrong, 0.01f * left_peak) << "the right ball's caustic in the left floor's map";
    EXPECT_LT(right_wrong, 0.01f * right_peak) << "the left ball's caustic in the right floor's map";
    // Mirror images: the same power under each ball.
    EXPECT_NEAR(left_peak, right_peak, 0.2f * left_peak);
}

TEST(PhotonsTool, BadInputGivesOneLineNamingTheFile) {
    const auto dir = test::fresh_dir("photons_bad");
    write_text(dir / "scene.json", k_scene);  // its pools do not exist
    test::ToolRun r = test::run_tool("prt-photons", (dir / "scene.json").string() + " --quiet", dir);
    EXPECT_EQ(r.code, 1);
    EXPECT_EQ(test::lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("floor.pool"), std::string::npos) << r.err;
    // A truncated pool.
    test::write_model_pool(test::make_model(test::sphere_points({0, 0, 0}, 1, 2000), {0, 0, 0}),
                           dir / "floor.pool");
    std::filesystem::resize_file(dir / "floor.pool", std::filesystem::file_size(dir / "floor.pool") / 2);
    r = test::run_tool("prt-photons", (dir / "scene.json").string() + " --quiet", dir);
    EXPECT_EQ(r.code, 1);
    EXPECT_EQ(test::lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("floor.pool"), std::string::npos) << r.err;
    r = test::run_tool("prt-photons", (dir / "scene.json").string() + " --face-res 0", dir);
    EXPECT_EQ(r.code, 2) << r.err;
}

TEST(PhotonsTool, BakesCausticsOnModelsWithoutASplatOctree) {
    // Issue 20: a floor traced as ISO (no splat octree: the frame comes from its points) under a glass
    // ball of Bezier patches; the floor's pool gets its caustic map and keeps having no octree.
    PRT_SKIP_WITHOUT_SURFACE_TOOLS();
    const test::TempDir dir("prt_photons_surfaces");
    test::write_points_pool(
        test::make_model(test::rect_points({-2, 0, -2}, {4, 0, 0}, {0, 0, 4}, {0, 1, 0}, 150), {0, 0, 0}),
        dir.path / "points.pool");
    test::must_run("prt-iso",
                   (dir.path / "points.pool").string() + " -o " + (dir.path / "floor.pool").string() + " -q",
                   dir.path);
    const double center[3] = {0, 0.8, 0};
    test::sphere_patch_file(dir.path, 0.4, center);
    test::must_run("prt-patches",
                   (dir.path / "sphere.bpt").string() + " -o " + (dir.path / "ball.pool").string() + " -q",
                   dir.path);
    auto replace_first = [](std::string text, const std::string& from, const std::string& to) {
        return text.replace(text.find(from), from.size(), to);
    };
    std::string scene =
        replace_first(k_scene, R"("material": "floor"})", R"("material": "floor", "surface": "iso"})");
    scene = replace_first(scene, R"("material": "glass"})", R"("material": "glass", "surface": "patches"})");
    write_text(dir.path / "scene.json", scene);
    test::ToolRun r = test::run_tool(
        "prt-photons", (dir.path / "scene.json").string() + " --face-res 96 --per-pixel 2 --backend cpu",
        dir.path);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("frame of the points"), std::string::npos) << r.err;
    const pool::PoolFile floor = pool::PoolFile::open(dir.path / "floor.pool");
    EXPECT_GT(rt::load_caustic_view(floor).tree.leaf_count, 0u);
    EXPECT_FALSE(floor.has(pool::SectionType::octree_info));
    EXPECT_TRUE(floor.has(pool::SectionType::iso_info));
}
