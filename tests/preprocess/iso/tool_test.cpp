// prt-iso end to end (PRT_BIN_DIR/prt-iso): exit codes 0 / 1 (bad input) / 2 (bad usage), one-line
// errors naming the file, --help documenting every option with its default, --quiet, statistics,
// carry-over of the input's sections and provenance, and a pool load_iso_view accepts.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "iso_test_util.h"
#include "point_cloud.h"
#include "preprocess/cloud_pool.h"
#include "prt/formats/pool.h"
#include "prt/runtime/surface_pools.h"
#include "runtime/tool_fixture.h"

namespace {

namespace fs = std::filesystem;
using namespace prt;

class IsoTool : public prt::test::ToolTest {
protected:
    IsoTool() : ToolTest("prt-iso", "prt_iso_tool_") {}
    /// A torus pool (positions, normals, colors; radii and normals optional), offset far from the
    /// origin so the local frame matters.
    std::string torus_pool(const std::string& name, bool radii, bool normals = true) {
        const iso_test::PointSet s = iso_test::synth_points(iso_test::torus_shape(1.0, 0.4), 8000, 0.0, true);
        pre::PointCloud c;
        for (std::size_t i = 0; i < s.positions.size(); ++i) {
            c.positions.push_back({s.positions[i].x + 1e5, s.positions[i].y, s.positions[i].z - 3e4});
            if (normals) c.normals.push_back(s.normals[i]);
            c.colors.push_back(s.colors[i]);
            if (radii) c.radii.push_back(0.05f);
        }
        return prt::test::write_cloud_pool(c, path(name));
    }
};

TEST_F(IsoTool, WritesAValidPoolWithStatistics) {
    const std::string in = torus_pool("in.pool", true);
    ASSERT_EQ(run(in + " -o " + path("out.pool") + " --storage both --stats-json " + path("stats.json")), 0)
        << m_stderr;
    const pool::PoolFile p = pool::PoolFile::open(path("out.pool"));
    const core::IsoView v = rt::load_iso_view(p);
    EXPECT_GT(v.leaf_count, 1000u);
    EXPECT_NE(v.leaves_q8, nullptr);
    EXPECT_NE(v.leaves_f32, nullptr);
    EXPECT_TRUE(p.has(pool::SectionType::radii));   // carried over
    EXPECT_TRUE(p.has(pool::SectionType::colors));  // carried over
    EXPECT_TRUE(v.flags & pool::k_iso_colors);
    EXPECT_FALSE(v.flags & pool::k_iso_radii_knn);  // auto picked the radii section
    const std::string prov = p.provenance_json();
    EXPECT_NE(prov.find("\"test\""), std::string::npos);
    EXPECT_NE(prov.find("\"prt-iso\""), std::string::npos);
    EXPECT_NE(prov.find("\"smoothing\""), std::string::npos);
    EXPECT_NE(m_stderr.find("filled leaves"), std::string::npos);
    std::ifstream js(path("stats.json"));
    const nlohmann::json j = nlohmann::json::parse(js);
    EXPECT_EQ(j["leaves"].get<std::uint64_t>(), v.leaf_count);
    EXPECT_EQ(j["points"].get<std::uint64_t>(), 8000u);
    // A ray through the torus tube (local frame: the pool's origin is the torus centre).
    core::IsoHit h;
    core::IsoStats st;
    ASSERT_TRUE(
        core::trace_iso(v, core::Vec3{1.0f, 3.0f, 0.0f}, core::Vec3{0, -1, 0}, 10.0f, false, {}, h, st));
    EXPECT_NEAR(h.t, 2.6f, 0.01f);
    EXPECT_GT(h.normal.y, 0.99f);
}

TEST_F(IsoTool, KnnRadiiLevelsAndQuiet) {
    const std::string in = torus_pool("in.pool", false);
    ASSERT_EQ(run(in + " -o " + path("out.pool") + " --min-level 4 --max-level 4 --storage f32 --quiet"), 0)
        << m_stderr;
    EXPECT_EQ(m_stderr, "");
    const pool::PoolFile p = pool::PoolFile::open(path("out.pool"));
    const core::IsoView v = rt::load_iso_view(p);
    EXPECT_TRUE(v.flags & pool::k_iso_radii_knn);
    EXPECT_EQ(v.leaves_q8, nullptr);
    EXPECT_EQ(p.array<pool::IsoInfo>(pool::SectionType::iso_info)[0].depth, 4u);
    // In place: the output may be the input.
    ASSERT_EQ(run(path("out.pool") + " -o " + path("out.pool") + " --quiet"), 0) << m_stderr;
    const pool::PoolFile p2 = pool::PoolFile::open(path("out.pool"));
    EXPECT_FALSE(p2.has(pool::SectionType::iso_leaves_f32));  // replaced by the q8 build
    EXPECT_TRUE(p2.has(pool::SectionType::iso_leaves_q8));
}

TEST_F(IsoTool, ErrorsAndHelp) {
    ASSERT_EQ(run("--help"), 0);
    for (const char* option :
         {"--min-level", "--max-level", "--max-points", "--smoothing", "--support", "--radius", "--knn",
          "--knn-clamp", "--storage", "--no-passive", "--no-balance", "--no-closure", "--keep-uncrossed",
          "--threads", "--stats-json", "--quiet"})
        EXPECT_NE(m_stdout.find(option), std::string::npos) << option;
    EXPECT_NE(m_stdout.find("=10"), std::string::npos);  // defaults shown (max level)
    EXPECT_NE(m_stdout.find("=q8"), std::string::npos);
    EXPECT_EQ(run(path("missing.pool") + " -o " + path("o.pool")), 1);
    EXPECT_NE(m_stderr.find("prt-iso: error:"), std::string::npos);
    EXPECT_NE(m_stderr.find("missing.pool"), std::string::npos);
    const std::string no_normals = torus_pool("nn.pool", false, false);
    EXPECT_EQ(run(no_normals + " -o " + path("o.pool")), 1);
    EXPECT_NE(m_stderr.find("no normals"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(path("o.pool")));
    const std::string in = torus_pool("in.pool", false);
    EXPECT_EQ(run(in + " -o " + path("o.pool") + " --radius radii"), 1);
    EXPECT_NE(m_stderr.find("prt-radii"), std::string::npos) << m_stderr;
    EXPECT_EQ(run(in + " -o " + path("o.pool") + " --min-level 6 --max-level 5"), 1);
    EXPECT_NE(m_stderr.find("min level"), std::string::npos) << m_stderr;
    EXPECT_EQ(run(in + " -o " + path("o.pool") + " --storage f16"), 2);
    EXPECT_EQ(run(in + " -o " + path("o.pool") + " --max-level 21"), 2);
    EXPECT_EQ(run(in), 2);  // no output
    EXPECT_EQ(std::count(m_stderr.begin(), m_stderr.end(), '\n'), 1) << m_stderr;
    EXPECT_EQ(run(in + " -o " + path("nofolder/o.pool")), 1);
    EXPECT_NE(m_stderr.find("does not exist"), std::string::npos) << m_stderr;
}

}  // namespace
