// Issue 15's fidelity cases on a reduced size, with its targets as assertions: every surface at the
// tools' defaults, measured by prt-fidelity (256 x 256, 6 views; the room from its scanner) against
// the real reference mesh or the analytic shape of a laser-scan simulation. The real-data cases
// skip where ../shared/data is absent.
//
//   case                                   holes     false hits   depth median  normal median
//   the ten bunny scans (a quarter of them) <= 0.3 %  <= 0.3 %     <= 0.25 sp.   <= 5 deg
//   one raw bunny scan (bun000)            <= 0.5 %  <= 0.5 %
//   armadillo / dragon decimated to 10 %   <= 1 %    <= 0.5 %     (splats; MLS: see below)
//   laser scans, range noise, 1 % outliers <= 0.3 %  <= 0.3 %     <= 0.25 sp.   <= 5 deg
//
// Falls short (asserted at what is met, so a regression still fails): the MLS surface of the
// decimated models leaves 4-6 % holes along silhouettes and thin parts, against the 1 % target
// (WS05's plane fit shrinks curved parts by about R^2 / (2 rho) when the spacing is large).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "../../runtime/tool_run.h"

namespace fs = std::filesystem;

namespace {

const std::string k_data = PRT_SHARED_DATA_DIR;

#ifdef PRT_TEST_HAVE_OPENMESH
constexpr bool k_have_openmesh = true;
#else
constexpr bool k_have_openmesh = false;  // the cases that read a mesh (reference or model) skip
#endif
constexpr const char* k_no_openmesh = "this build has no OpenMesh: prt-import and prt-fidelity read no mesh";

struct Bounds {
    double holes, false_hits, depth = 1e9, normal_deg = 1e9;
};

class FidelityCases : public ::testing::Test {
protected:
    void SetUp() override {
        for (const char* t : {"prt-import", "prt-synth", "prt-radii", "prt-octree", "prt-cull", "prt-iso",
                              "prt-mls", "prt-fidelity"})
            if (!fs::exists(fs::path(PRT_BIN_DIR) / t))
                GTEST_SKIP() << t << " is not built (FLANN, OpenMesh or PCL missing)";
        m_dir = fs::temp_directory_path() / ("prt_fidelity_cases_" + std::to_string(::getpid()) + "_" +
                                             ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
    }
    void TearDown() override {
        if (!HasFailure()) fs::remove_all(m_dir);
    }

    void tool(const std::string& name, const std::string& args) {
        const auto r = prt::test::run_tool(name, args + " -q", m_dir);
        ASSERT_EQ(r.code, 0) << name << " " << args << ": " << r.err;
    }

    /// Every surface of `pool` at the defaults, then prt-fidelity; returns its JSON.
    nlohmann::json measure(const fs::path& pool, const std::string& fidelity_args) {
        for (const char* step : {"prt-radii", "prt-octree", "prt-cull", "prt-iso", "prt-mls"}) {
            tool(step, pool.string() + " -o " + pool.string());
            if (HasFatalFailure()) return {};
        }
        const fs::path js = m_dir / "fidelity.json";
        tool("prt-fidelity",
             pool.string() + " --width 256 --height 256 --json " + js.string() + " " + fidelity_args);
        if (HasFatalFailure()) return {};
        std::ifstream f(js);
        return nlohmann::json::parse(f);
    }

    static void expect(const nlohmann::json& j, const std::string& surface, const Bounds& b) {
        SCOPED_TRACE(surface);
        const auto& s = j.at("surfaces").at(surface);
        EXPECT_GT(s["covered_pixels"].get<double>(), 5000.0);
        EXPECT_LE(s["hole_rate"].get<double>(), b.holes);
        EXPECT_LE(s["false_hit_rate"].get<double>(), b.false_hits);
        EXPECT_LE(s["depth_error_spacings"]["median"].get<double>(), b.depth);
        EXPECT_LE(s["normal_error_degrees"]["median"].get<double>(), b.normal_deg);
    }

    fs::path m_dir;
};

bool have(const std::string& rel) {
    return fs::exists(fs::path(k_data) / rel);
}

}  // namespace

TEST_F(FidelityCases, BunnyTenScansAQuarterOfThePoints) {
    if (!k_have_openmesh) GTEST_SKIP() << k_no_openmesh;
    if (!have("points/stanford_bunny/data/bun.conf"))
        GTEST_SKIP() << k_data << ": the bunny scans are absent";
    const fs::path pool = m_dir / "bunny.pool";
    tool("prt-import", "--poses " + k_data + "/points/stanford_bunny/data/bun.conf --keep-fraction 0.25 -o " +
                           pool.string());
    if (HasFatalFailure()) return;
    const auto j =
        measure(pool, "--reference " + k_data + "/points/stanford_bunny/reconstruction/bun_zipper.ply");
    if (HasFatalFailure()) return;
    for (const char* s : {"splats", "iso", "mls"}) expect(j, s, {0.003, 0.003, 0.25, 5.0});
}

TEST_F(FidelityCases, OneRawBunnyScanInTheRegionItSaw) {
    if (!k_have_openmesh) GTEST_SKIP() << k_no_openmesh;
    if (!have("points/stanford_bunny/data/bun000.ply"))
        GTEST_SKIP() << k_data << ": the bunny scans are absent";
    const fs::path pool = m_dir / "bun000.pool";
    const std::string d = k_data + "/points/stanford_bunny/data/";
    tool("prt-import", "--poses " + d + "bun.conf " + d + "bun000.ply -o " + pool.string());
    if (HasFatalFailure()) return;
    const auto j =
        measure(pool, "--reference " + k_data + "/points/stanford_bunny/reconstruction/bun_zipper.ply");
    if (HasFatalFailure()) return;
    EXPECT_GT(j["reference_pixels"]["uncovered"].get<double>(), 10000.0) << "one scan sees part of the bunny";
    for (const char* s : {"splats", "iso", "mls"}) expect(j, s, {0.005, 0.005});
}

TEST_F(FidelityCases, MeshSampledModelsDecimatedToTenPercent) {
    if (!k_have_openmesh) GTEST_SKIP() << k_no_openmesh;
    for (const auto& [mesh, rel] :
         {std::pair<std::string, std::string>{"armadillo", "points/stanford_armadillo/armadillo.off"},
          {"dragon", "points/stanford_dragon/dragon_small.obj"}}) {
        SCOPED_TRACE(mesh);
        if (!have(rel)) GTEST_SKIP() << k_data << "/" << rel << " is absent";
        const fs::path pool = m_dir / (mesh + ".pool");
        tool("prt-import", k_data + "/" + rel + " --keep-fraction 0.1 -o " + pool.string());
        if (HasFatalFailure()) return;
        const auto j = measure(pool, "--surface splats,mls --reference " + k_data + "/" + rel);
        if (HasFatalFailure()) return;
        expect(j, "splats", {0.01, 0.005});
        expect(j, "mls", {0.06, 0.005});  // target 1 % holes: not met (see the header)
    }
}

TEST_F(FidelityCases, LaserScansWithRangeNoiseAndOutliers) {
    // A sphere seen by three scanners, and the room scanned from inside it (judged from the scanner).
    const fs::path sphere = m_dir / "sphere.pool", room = m_dir / "room.pool";
    tool("prt-synth",
         "sphere --scan --scanners 3 --sample-step 0.1 --range-noise 0.0005 --outliers 0.01 -o " +
             sphere.string());
    tool("prt-import", sphere.string() + " -o " + sphere.string());
    if (HasFatalFailure()) return;
    const auto a = measure(sphere, "");
    if (HasFatalFailure()) return;
    EXPECT_EQ(a["reference"]["kind"], "analytic");
    for (const char* s : {"splats", "iso", "mls"}) expect(a, s, {0.003, 0.003, 0.25, 5.0});

    tool("prt-synth",
         "room --scan --sample-step 0.4 --range-noise 0.0005 --outliers 0.01 -o " + room.string());
    tool("prt-import", room.string() + " -o " + room.string());
    if (HasFatalFailure()) return;
    const auto b = measure(room, "--views-from sensors");
    if (HasFatalFailure()) return;
    for (const char* s : {"splats", "iso", "mls"}) expect(b, s, {0.003, 0.003, 0.25, 5.0});
}
