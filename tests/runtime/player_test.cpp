// prt-play and prt-bench end to end (label cpu): headless rendering of a pool to PPM, the default
// scene, one-line errors (no GPU, missing sections, unwritable formats), and the benchmark's JSON.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "prt/runtime/backend.h"
#include "prt/runtime/image.h"
#include "test_scene.h"
#include "tool_fixture.h"
#include "tool_run.h"

namespace prt::test {
namespace {

namespace fs = std::filesystem;

class PlayerTest : public FolderTest {
protected:
    PlayerTest() : FolderTest("prt_player_test_") {}
    void SetUp() override {
        FolderTest::SetUp();
        const auto ball = make_pool(
            make_model(sphere_points({10, 20, 30}, 1.0, 4000, false, {250, 60, 40, 255}), {10, 20, 30}));
        write_pool(*ball, m_dir / "ball.pool");
    }
    /// prt-play --headless on `pool` (in the folder) with `args`, writing `out` (in the folder).
    ToolRun play(const std::string& pool, const std::string& args, const std::string& out) const {
        return run_tool("prt-play",
                        (m_dir / pool).string() + " --headless " + args + " --out " + (m_dir / out).string(),
                        m_dir);
    }
};

/// A failure of exit code 1 with one line on stderr that holds each of `words`.
void expect_one_line_error(const ToolRun& r, std::initializer_list<const char*> words) {
    EXPECT_EQ(r.code, 1);
    expect_one_line(r.err, words);
}

TEST_F(PlayerTest, RendersAPoolAloneToPpm) {
    const fs::path out = m_dir / "ball.ppm";
    const ToolRun r = play("ball.pool", "--backend cpu --width 40 --height 30", "ball.ppm");
    ASSERT_EQ(r.code, 0) << r.err;
    const rt::Image img = rt::read_ppm(out);
    EXPECT_EQ(img.width, 40u);
    EXPECT_EQ(img.height, 30u);
    // The default camera frames the model: the centre is the red ball, the corner the background.
    const std::uint32_t centre = img.rgba8[15 * 40 + 20], corner = img.rgba8[0];
    EXPECT_GT(centre & 0xff, 2 * ((centre >> 8) & 0xff)) << "centre pixel is not the red ball";
    EXPECT_NE(centre, corner);
    EXPECT_NE(r.err.find("load"), std::string::npos) << "the load time is reported";
}

TEST_F(PlayerTest, QuietAndFramesAndPfm) {
    const ToolRun r =
        play("ball.pool", "--quiet --backend cpu --width 16 --height 16 --frames 3 --orbit 30", "f_%02d.pfm");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(r.err.empty()) << "--quiet must silence stderr: " << r.err;
    for (int f = 0; f < 3; ++f) {
        char name[32];
        std::snprintf(name, sizeof(name), "f_%02d.pfm", f);
        const rt::FloatImage img = rt::read_pfm(m_dir / name);
        EXPECT_EQ(img.width, 16u);
        for (float v : img.rgb) EXPECT_TRUE(std::isfinite(v));
    }
}

TEST_F(PlayerTest, CudaWithoutDeviceFailsWithOneLine) {
    const rt::BackendAvailability a = rt::backend_availability();
    if (a.cuda_device) GTEST_SKIP() << "a CUDA device exists here: nothing to refuse";
    expect_one_line_error(play("ball.pool", "--backend cuda", "x.ppm"), {"cuda"});
    EXPECT_FALSE(fs::exists(m_dir / "x.ppm"));
    // auto falls back to the CPU.
    const ToolRun ok = play("ball.pool", "-q --width 8 --height 8", "y.ppm");
    EXPECT_EQ(ok.code, 0) << ok.err;
}

TEST_F(PlayerTest, ErrorsNameTheFileAndTheProblem) {
    // A pool without the octree sections.
    pool::PoolWriter w;
    auto full = make_pool(make_model(sphere_points({0, 0, 0}, 1.0, 500), {0, 0, 0}));
    w.carry_over(*full);
    for (auto t : {pool::SectionType::octree_info, pool::SectionType::octree_nodes,
                   pool::SectionType::leaf_info, pool::SectionType::splats})
        w.remove(t);
    w.write(m_dir / "points.pool");
    expect_one_line_error(play("points.pool", "--backend cpu", "z.ppm"), {"points.pool", "octree"});
    // An output format this build cannot write.
    const ToolRun bad = play("ball.pool", "--backend cpu", "z.unknownext");
    EXPECT_NE(bad.code, 0);
    EXPECT_EQ(lines(bad.err), 1) << bad.err;
    // No input at all is a usage error.
    const ToolRun none = run_tool("prt-play", "--headless", m_dir);
    EXPECT_NE(none.code, 0);
}

TEST_F(PlayerTest, MissingInputFilesExitWithStatus1AndOneLine) {
    const std::string none = (m_dir / "none.pool").string();
    const std::string out = " --out " + (m_dir / "x.ppm").string();
    // The pool, the scene file and the camera path of prt-play; prt-bench's pool and scene.
    for (const std::string& args :
         {none + " --headless" + out, (m_dir / "ball.pool").string() + " --scene " + none + out,
          (m_dir / "ball.pool").string() + " --camera-path " + none + out}) {
        SCOPED_TRACE(args);
        const ToolRun r = run_tool("prt-play", args, m_dir);
        expect_one_line_error(r, {"prt-play: error: ", "none.pool: no such file"});
    }
    for (const std::string& args : {none + " --frames 1", "--scene " + none}) {
        SCOPED_TRACE(args);
        expect_one_line_error(run_tool("prt-bench", args, m_dir),
                              {"prt-bench: error: ", "none.pool: no such file"});
    }
    // A folder given as the pool.
    expect_one_line_error(run_tool("prt-play", m_dir.string() + out, m_dir), {"is a folder"});
    EXPECT_FALSE(fs::exists(m_dir / "x.ppm"));
}

TEST_F(PlayerTest, UnwritableOutputIsRefusedBeforeRendering) {
    const std::string pool = (m_dir / "ball.pool").string() + " --backend cpu --width 16 --height 16";
    fs::create_directory(m_dir / "taken.ppm");
    for (const fs::path& out : {m_dir / "no" / "such" / "x.ppm", m_dir / "taken.ppm"}) {
        SCOPED_TRACE(out.string());
        const ToolRun r = run_tool("prt-play", pool + " --out " + out.string(), m_dir);
        // One line, and nothing before it: the pool was not even loaded, no frame rendered.
        expect_one_line_error(r, {"prt-play: error: ", out.string().c_str(), "cannot write"});
    }
    const ToolRun frames =
        run_tool("prt-play", pool + " --frames 2 --out " + (m_dir / "none" / "f_%02d.ppm").string(), m_dir);
    expect_one_line_error(frames, {"none/f_00.ppm", "cannot write"});
    const ToolRun bench =
        run_tool("prt-bench", pool + " --frames 1 --json " + (m_dir / "no" / "b.json").string(), m_dir);
    expect_one_line_error(bench, {"prt-bench: error: ", "b.json", "cannot write"});
    if (::geteuid() != 0) {  // root writes into read-only folders anyway
        fs::create_directory(m_dir / "ro");
        fs::permissions(m_dir / "ro", fs::perms::owner_read | fs::perms::owner_exec);
        const ToolRun r = run_tool("prt-play", pool + " --out " + (m_dir / "ro" / "x.ppm").string(), m_dir);
        fs::permissions(m_dir / "ro", fs::perms::owner_all);
        expect_one_line_error(r, {"ro/x.ppm", "cannot write", "Permission denied"});
    }
}

TEST_F(PlayerTest, ProgressOnAPipeIsWholeLines) {
    // Enough frames for the progress (stderr to a file: not a terminal) to print more than once.
    const ToolRun r = play("ball.pool", "--backend cpu --width 24 --height 24 --frames 300", "p.ppm");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err.find('\r'), std::string::npos) << r.err;
    ASSERT_FALSE(r.err.empty());
    EXPECT_EQ(r.err.back(), '\n');
    EXPECT_NE(r.err.find("prt-play: rendering: done in"), std::string::npos) << r.err;
}

TEST_F(PlayerTest, HelpKeysListsTheWindowControls) {
    const ToolRun r = run_tool("prt-play", "--help-keys", m_dir);
    EXPECT_EQ(r.code, 0) << r.err;
    for (const char* k : {"W A S D", "pick", "path tracing", "screenshot", "camera path", "Esc"})
        EXPECT_NE(r.out.find(k), std::string::npos) << k << ": " << r.out;
    const ToolRun bad = run_tool("prt-play", (m_dir / "ball.pool").string() + " --keys Xyz", m_dir);
    EXPECT_EQ(bad.code, 2) << bad.err;
}

/// Whether pixel (x, y) of a PPM render is the red ball (red well above green).
bool red_at(const rt::Image& img, std::uint32_t x, std::uint32_t y) {
    const std::uint32_t p = img.rgba8[y * img.width + x];
    return (p & 0xff) > 2 * ((p >> 8) & 0xff) + 10;
}

TEST_F(PlayerTest, CameraFromTheCommandLine) {
    const std::string pool =
        (m_dir / "ball.pool").string() + " --headless -q --backend cpu --width 40 --height 40";
    auto play = [&](const std::string& args) {
        const fs::path out = m_dir / "cam.ppm";
        fs::remove(out);
        const ToolRun r = run_tool("prt-play", pool + " --out " + out.string() + " " + args, m_dir);
        EXPECT_EQ(r.code, 0) << args << ": " << r.err;
        return r.code == 0 ? rt::read_ppm(out) : rt::Image{};
    };
    // The ball (radius 1 at (10, 20, 30)) seen from 10 away with a 30-degree fov covers
    // tan(asin(0.1)) / tan(15 deg) = 0.37 of the half height: the centre is red, x = 5 is not.
    rt::Image img = play("--eye 10,20,40 --look-at 10,20,30 --up 0,1,0 --fov 30");
    ASSERT_EQ(img.width, 40u);
    EXPECT_TRUE(red_at(img, 20, 20));
    EXPECT_FALSE(red_at(img, 5, 20));
    EXPECT_FALSE(red_at(img, 20, 5));
    // With a 5-degree fov the ball fills the image.
    img = play("--eye 10,20,40 --look-at 10,20,30 --fov 5");
    EXPECT_TRUE(red_at(img, 0, 0));
    EXPECT_TRUE(red_at(img, 39, 39));
    // --eye alone looks at the model's centre.
    img = play("--eye 16,20,30");
    EXPECT_TRUE(red_at(img, 20, 20));
    // --look-at alone moves the default view: 0.5 to the right of the ball puts it left of centre
    // (the default view frames the radius-1 ball at 1 / 1.05 of the half height).
    img = play("--look-at 10.5,20,30");
    EXPECT_TRUE(red_at(img, 11, 20));
    EXPECT_FALSE(red_at(img, 36, 20));
    // The same camera given by a scene file renders the same image.
    const fs::path scene = m_dir / "cam.json";
    std::ofstream(scene)
        << R"({"camera": {"position": [10, 20, 40], "look_at": [10, 20, 30], "fov_y_degrees": 30,
        "width": 40, "height": 40}, "lights": [{"type": "point", "position": [10, 30, 40]}],
        "models": [{"pool": "ball.pool"}]})";
    const fs::path a = m_dir / "a.ppm", b = m_dir / "b.ppm";
    ASSERT_EQ(
        run_tool("prt-play", "--scene " + scene.string() + " --headless -q --backend cpu --out " + a.string(),
                 m_dir)
            .code,
        0);
    ASSERT_EQ(run_tool("prt-play",
                       "--scene " + scene.string() +
                           " --headless -q --backend cpu --eye 14,20,30 --fov 60 --out " + b.string(),
                       m_dir)
                  .code,
              0);
    EXPECT_NE(rt::read_ppm(a).rgba8, rt::read_ppm(b).rgba8) << "--eye and --fov replace the scene camera's";
}

TEST_F(PlayerTest, CameraOptionErrorsAreUsageErrors) {
    const std::string pool = (m_dir / "ball.pool").string() + " --headless --backend cpu --out " +
                             (m_dir / "e.ppm").string() + " ";
    const fs::path scene = m_dir / "look_z.json";
    std::ofstream(scene) << R"({"camera": {"position": [10, 20, 40], "look_at": [10, 20, 30]},
        "models": [{"pool": "ball.pool"}]})";
    const std::pair<std::string, std::string> cases[] = {
        {pool + "--eye 1,2,3 --look-at 1,2,3", "equals"},
        {pool + "--eye 0,0,0 --look-at 0,5,0 --up 0,-1,0", "parallel"},
        {pool + "--eye nan,0,0", "not a finite number"},
        {pool + "--look-at 1,2", "X,Y,Z"},
        {pool + "--up 0,0,0", "zero vector"},
        {pool + "--fov 180", "(0, 180)"},
        {pool + "--fov nan", "(0, 180)"},
        // Looking straight down with the default +y up: the up is the view direction.
        {pool + "--eye 10,25,30 --look-at 10,20,30", "parallel"},
        {pool + "--look-at 10,20,30 --eye 10,10,30 --up auto", "parallel"},
        // The scene camera looks along -z: --up 0,0,1 is along the view.
        {"--scene " + scene.string() + " --headless --backend cpu --out " + (m_dir / "e.ppm").string() +
             " --up 0,0,1",
         "parallel"},
    };
    for (const auto& [args, what] : cases) {
        const ToolRun r = run_tool("prt-play", args, m_dir);
        EXPECT_EQ(r.code, 2) << args << ": " << r.err;
        EXPECT_EQ(lines(r.err), 1) << args << ": " << r.err;
        EXPECT_NE(r.err.find(what), std::string::npos) << args << ": " << r.err;
        EXPECT_FALSE(fs::exists(m_dir / "e.ppm")) << args;
    }
    // prt-bench shares the options.
    const ToolRun bench =
        run_tool("prt-bench",
                 (m_dir / "ball.pool").string() +
                     " --backend cpu --width 8 --height 8 --frames 1 --warmup 0 --scenarios primary "
                     "--eye 10,25,30 --look-at 10,20,30 -q",
                 m_dir);
    EXPECT_EQ(bench.code, 2) << bench.err;
    EXPECT_EQ(lines(bench.err), 1) << bench.err;
}

TEST_F(PlayerTest, UpAutoSaysWhichRuleDecided) {
    const ToolRun r = run_tool("prt-play",
                               (m_dir / "ball.pool").string() +
                                   " --headless --backend cpu --width 16 --height 16 --up auto --out " +
                                   (m_dir / "u.ppm").string(),
                               m_dir);
    ASSERT_EQ(r.code, 0) << r.err;
    // A ball: no plane and no sensors, so +y.
    EXPECT_NE(r.err.find("prt-play: --up auto: +y: no dominant plane"), std::string::npos) << r.err;
}

TEST(GpuBackend, WithoutDeviceTheFactoryThrowsOneClearLine) {
    const rt::BackendAvailability a = rt::backend_availability();
    if (a.cuda_device) GTEST_SKIP() << "a CUDA device exists here";
    for (const char* name : {"cuda", "hybrid"}) {
        try {
            rt::make_backend(name);
            ADD_FAILURE() << name << " must throw without a device";
        } catch (const Error& e) {
            const std::string m = e.what();
            EXPECT_EQ(m.find('\n'), std::string::npos);
            EXPECT_NE(m.find(name), std::string::npos) << m;
        }
    }
    EXPECT_EQ(rt::make_backend("auto")->name(), "cpu");
    EXPECT_THROW(rt::make_backend("vulkan"), Error);
}

TEST_F(PlayerTest, BenchWritesJsonWithEveryScenario) {
    const fs::path json = m_dir / "bench.json";
    const ToolRun r = run_tool(
        "prt-bench",
        "--synthetic 3000 --width 24 --height 24 --frames 3 --warmup 1 --backend cpu --quiet --json " +
            json.string(),
        m_dir);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(slurp(json));
    EXPECT_EQ(j["backend"], "cpu");
    ASSERT_EQ(j["scenarios"].size(), 3u);
    for (const auto& s : j["scenarios"]) {
        EXPECT_GT(s["median_ms"].get<double>(), 0.0);
        EXPECT_EQ(s["primary"].get<std::uint64_t>(), 24u * 24u);  // the camera is inside the room
        // every timed frame's milliseconds, whose median is median_ms; no CUDA queue on the CPU
        std::vector<double> ms = s["frames_ms"].get<std::vector<double>>();
        ASSERT_EQ(ms.size(), 3u);
        std::sort(ms.begin(), ms.end());
        EXPECT_DOUBLE_EQ(ms[1], s["median_ms"].get<double>());
        EXPECT_EQ(s["frames_heavy_first_items"].size(), 3u);
        EXPECT_EQ(s["heavy_first_frames"].get<std::uint64_t>(), 0u);
    }
    EXPECT_GT(j["scenarios"][1]["shadow"].get<std::uint64_t>(), 0u);
    // 4 bounces in a closed room: nearly every reflected ray hits again (a sparse 3000-point
    // sampling leaves a few gaps at the room's edges).
    EXPECT_GE(j["scenarios"][2]["secondary"].get<double>(), 0.97 * 4 * 24 * 24);
    EXPECT_LE(j["scenarios"][2]["secondary"].get<std::uint64_t>(), 4u * 24u * 24u);
    EXPECT_NE(r.out.find("Grays/s"), std::string::npos) << "the table goes to stdout";
}

TEST_F(PlayerTest, BenchRefusesASurfaceTheSyntheticRoomLacks) {
    // The synthetic room holds splats only: asking for ISO must not time splats under its name.
    const fs::path json = m_dir / "iso.json";
    const ToolRun r = run_tool("prt-bench",
                               "--synthetic 3000 --width 8 --height 8 --frames 1 --warmup 0 --backend cpu "
                               "--surface iso --quiet --json " +
                                   json.string(),
                               m_dir);
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("synthetic room: no ISO sections (run prt-iso)"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(json));
    EXPECT_EQ(run_tool("prt-bench",
                       "--synthetic 3000 --width 8 --height 8 --frames 1 --warmup 0 --backend cpu --surface "
                       "splats --quiet",
                       m_dir)
                  .code,
              0);
}

TEST_F(PlayerTest, BenchProfileSplitsTheWorkByRayKindAndDepth) {
    const fs::path json = m_dir / "profile.json";
    const ToolRun r =
        run_tool("prt-bench",
                 "--synthetic 3000 --width 16 --height 16 --frames 1 --warmup 0 --backend cpu --quiet "
                 "--profile --json " +
                     json.string(),
                 m_dir);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(slurp(json));
    // Per ray kind from the scenarios: shadow rays leave their surface, so its leaves' bounds pass
    // them (the normal cones), and they test far fewer splats than primary rays.
    const auto& k = j["per_ray_kind"];
    EXPECT_GT(k["shadow"]["culled_leaves_per_ray"].get<double>(), 0.0);
    EXPECT_LT(k["shadow"]["splat_tests_per_ray"].get<double>(),
              k["primary"]["splat_tests_per_ray"].get<double>());
    // The host profile: primary + 4 bounces, then shadow rays; efficiencies in (0, 1].
    const auto& kinds = j["profile"]["reflect4"]["kinds"];
    ASSERT_EQ(kinds.size(), 6u);
    EXPECT_EQ(kinds[0]["kind"], "primary");
    EXPECT_EQ(kinds[4]["kind"], "bounce 4");
    EXPECT_EQ(kinds[0]["rays"].get<std::uint64_t>(), 256u);
    for (const auto& [name, value] : j["profile"]["reflect4"]["simt_efficiency"].items()) {
        EXPECT_GT(value.get<double>(), 0.0) << name;
        EXPECT_LE(value.get<double>(), 1.0) << name;
    }
    EXPECT_NE(r.out.find("SIMT efficiency"), std::string::npos) << r.out;
}

TEST_F(PlayerTest, EmbreePeerBenchmarkTracesTheSameSurface) {
#ifndef PRT_TEST_HAVE_EMBREE
    GTEST_SKIP() << "prt-bench-embree is not built (no Embree 3: libembree-dev)";
#endif
    const fs::path json = m_dir / "embree.json";
    const ToolRun r =
        run_tool("prt-bench-embree",
                 "--synthetic 4000 --width 32 --height 32 --frames 1 --warmup 0 --threads 2 --quiet --json " +
                     json.string(),
                 m_dir);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(slurp(json));
    ASSERT_EQ(j["scenarios"].size(), 3u);
    for (const auto& s : j["scenarios"]) {
        EXPECT_GT(s["ratio_ours_over_embree"].get<double>(), 0.0);
        // The same rays: every pixel's primary ray, the same shadow and secondary rays within 2%.
        EXPECT_NEAR(s["embree_rays"].get<double>(), s["ours_rays"].get<double>(),
                    0.02 * s["ours_rays"].get<double>());
        EXPECT_LT(s["mean_abs_diff_8bit"].get<double>(), 8.0) << s["name"];
    }
    const auto& a = j["primary_agreement"];
    EXPECT_GE(a["same_distance"].get<double>(), 0.95 * a["both_hit"].get<double>());
    EXPECT_NE(r.out.find("ours/Embree"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace prt::test

// ---- issue 10 (reliability): a missing device ----------------------------------------------------
namespace prt::test {
namespace {

/// How often `needle` occurs in `s`.
int occurrences(const std::string& s, const std::string& needle) {
    int n = 0;
    for (std::size_t at = s.find(needle); at != std::string::npos; at = s.find(needle, at + needle.size()))
        ++n;
    return n;
}

TEST_F(PlayerTest, MissingDeviceIsOneLineAndAutoFallsBackWithOneNote) {
    const rt::BackendAvailability a = rt::backend_availability();
    if (a.cuda_device) GTEST_SKIP() << "a CUDA device exists here: nothing is missing";
    ASSERT_FALSE(a.cuda_why.empty());
    const std::string pool = (m_dir / "ball.pool").string();
    const std::string small = " --width 8 --height 8";
    const std::string bench_args = small + " --frames 1 --warmup 0 --json ";

    // cuda and hybrid: prt-play and prt-bench print exactly one line, the reason, exit 1 and
    // write nothing.
    for (const std::string backend : {"cuda", "hybrid"}) {
        SCOPED_TRACE(backend);
        const ToolRun play = run_tool(
            "prt-play",
            pool + " --headless --backend " + backend + small + " --out " + (m_dir / "x.ppm").string(),
            m_dir);
        const ToolRun bench = run_tool(
            "prt-bench", pool + " --backend " + backend + bench_args + (m_dir / "x.json").string(), m_dir);
        for (const ToolRun* r : {&play, &bench}) {
            EXPECT_EQ(r->code, 1);
            EXPECT_EQ(lines(r->err), 1) << r->err;
            EXPECT_NE(r->err.find("error: --backend " + backend + ": " + a.cuda_why), std::string::npos)
                << r->err;
        }
        EXPECT_FALSE(fs::exists(m_dir / "x.ppm"));
        EXPECT_FALSE(fs::exists(m_dir / "x.json"));
    }

    // auto: renders on the CPU, and the backend line says once why the GPU was not used.
    const std::string note = "backend cpu on CPU";
    const std::string why = "(--backend auto: " + a.cuda_why + ")";
    const fs::path image = m_dir / "auto.ppm";
    const ToolRun play =
        run_tool("prt-play", pool + " --headless --backend auto" + small + " --out " + image.string(), m_dir);
    ASSERT_EQ(play.code, 0) << play.err;
    EXPECT_TRUE(fs::exists(image));
    EXPECT_EQ(occurrences(play.err, a.cuda_why), 1) << play.err;
    EXPECT_NE(play.err.find(why), std::string::npos) << play.err;
    EXPECT_NE(play.err.find(note), std::string::npos) << play.err;
    EXPECT_EQ(play.err.find("error"), std::string::npos) << play.err;
    // --quiet silences the note with the rest.
    const ToolRun quiet = run_tool(
        "prt-play", pool + " --headless -q --backend auto" + small + " --out " + image.string(), m_dir);
    EXPECT_EQ(quiet.code, 0) << quiet.err;
    EXPECT_EQ(quiet.err, "");
    // prt-bench: the same note, and the JSON report records it with the device.
    const fs::path json = m_dir / "auto.json";
    const ToolRun bench = run_tool("prt-bench", pool + " --backend auto" + bench_args + json.string(), m_dir);
    ASSERT_EQ(bench.code, 0) << bench.err;
    EXPECT_EQ(occurrences(bench.err + bench.out, a.cuda_why), 1)
        << bench.err << bench.out;  // its summary line
    const auto report = nlohmann::json::parse(slurp(json));
    EXPECT_EQ(report["backend"], "cpu");
    EXPECT_NE(report["device"].get<std::string>().find(why), std::string::npos) << report["device"];
}

}  // namespace
}  // namespace prt::test
