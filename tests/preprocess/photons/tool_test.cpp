// End-to-end tests of the prt-photons tool: --help, sections written into the pools in place,
// removed when a pool gets no deposit, one-line errors naming the file, no partial output.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "gi_test_util.h"
#include "prt/runtime/gi_pool.h"
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
