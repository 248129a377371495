// prt-mls end to end (PRT_BIN_DIR/prt-mls): exit codes 0 / 1 (bad pool) / 2 (bad usage), one-line
// errors naming the file and the section, --help with defaults, --quiet, statistics, carry-over
// of the input's sections, and a pool load_mls_view accepts.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "mls_test_util.h"
#include "point_cloud.h"
#include "preprocess/cloud_pool.h"
#include "prt/formats/pool.h"
#include "prt/runtime/surface_pools.h"
#include "runtime/tool_fixture.h"

namespace {

namespace fs = std::filesystem;
using namespace prt;

class MlsTool : public prt::test::ToolTest {
protected:
    MlsTool() : ToolTest("prt-mls", "prt_mls_tool_") {}
    /// A sphere pool with positions and normals, and radii unless `radii` is false.
    std::string sphere_pool(const std::string& name, bool radii = true) {
        const mls_test::PointSet s = mls_test::fibonacci_sphere(1500);
        pre::PointCloud c;
        for (std::size_t i = 0; i < s.positions.size(); ++i) {
            c.positions.push_back({s.positions[i].x, s.positions[i].y, s.positions[i].z});
            c.normals.push_back(s.normals[i]);
            if (radii) c.radii.push_back(s.radii[i]);
        }
        return prt::test::write_cloud_pool(c, path(name));
    }
};

TEST_F(MlsTool, WritesAValidPoolWithStatistics) {
    const std::string in = sphere_pool("in.pool");
    ASSERT_EQ(run(in + " -o " + path("out.pool") + " --stats-json " + path("stats.json")), 0) << m_stderr;
    const pool::PoolFile p = pool::PoolFile::open(path("out.pool"));
    const core::MlsView v = rt::load_mls_view(p);
    EXPECT_EQ(v.splat_count, 1500u);
    EXPECT_TRUE(p.has(pool::SectionType::radii));  // carried over
    EXPECT_NE(p.provenance_json().find("\"test\""), std::string::npos);
    EXPECT_NE(p.provenance_json().find("\"prt-mls\""), std::string::npos);
    EXPECT_NE(p.provenance_json().find("\"support_factor\""), std::string::npos);
    EXPECT_NE(m_stderr.find("kd-tree"), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("shrinking"), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("BVH over the non-empty leaves"), std::string::npos) << m_stderr;
    EXPECT_NE(v.bvh_nodes, nullptr);
    EXPECT_TRUE(p.has(pool::SectionType::mls_bvh_nodes) && p.has(pool::SectionType::mls_bvh_leaves));
    EXPECT_EQ(m_stdout, "");
    const std::string stats = prt::test::slurp(path("stats.json"));
    for (const char* key : {"\"nodes\"", "\"refs_per_leaf\"", "\"culled_leaves\"", "\"collapsed\"",
                            "\"seconds_total\"", "\"bvh_nodes\"", "\"bvh_depth\""})
        EXPECT_NE(stats.find(key), std::string::npos) << key;
    // Rebuilding over the output replaces the tree; --quiet prints nothing.
    ASSERT_EQ(run(path("out.pool") + " -o " + path("out.pool") + " --quiet --no-shrink --support-factor 1.5"),
              0)
        << m_stderr;
    EXPECT_EQ(m_stderr, "");
    const pool::PoolFile p2 = pool::PoolFile::open(path("out.pool"));
    EXPECT_EQ(p2.array<pool::MlsInfo>(pool::SectionType::mls_info)[0].support_factor, 1.5f);
    EXPECT_EQ(p2.array<pool::MlsInfo>(pool::SectionType::mls_info)[0].flags & pool::k_mls_shrunk, 0u);
    // --no-bvh over a pool with a BVH drops it (it would not match the new tree): the kd walk.
    ASSERT_EQ(run(path("out.pool") + " -o " + path("out.pool") + " --quiet --no-bvh"), 0) << m_stderr;
    const pool::PoolFile p3 = pool::PoolFile::open(path("out.pool"));
    EXPECT_FALSE(p3.has(pool::SectionType::mls_bvh_nodes));
    EXPECT_FALSE(p3.has(pool::SectionType::mls_bvh_leaves));
    EXPECT_EQ(rt::load_mls_view(p3).bvh_nodes, nullptr);
}

TEST_F(MlsTool, MissingRadiiIsAOneLineError) {
    const std::string in = sphere_pool("noradii.pool", false);
    EXPECT_EQ(run(in + " -o " + path("out.pool")), 1);
    prt::test::expect_one_line(m_stderr, {"noradii.pool", "radii", "prt-radii"});
    EXPECT_FALSE(fs::exists(path("out.pool")));
    EXPECT_EQ(run(path("nothing.pool") + " -o " + path("out.pool")), 1);
    EXPECT_NE(m_stderr.find("nothing.pool"), std::string::npos) << m_stderr;
}

TEST_F(MlsTool, UsageErrorsAndHelp) {
    const std::string in = sphere_pool("in.pool");
    EXPECT_EQ(run(in + " -o " + path("o.pool") + " --support-factor -1"), 2);
    EXPECT_EQ(run(in + " -o " + path("o.pool") + " --shrink-axes 2"), 2);
    EXPECT_EQ(run(in), 2);  // no -o
    EXPECT_FALSE(fs::exists(path("o.pool")));
    ASSERT_EQ(run("--help"), 0);
    for (const char* opt : {"--support-factor", "--samples", "--slices", "--shrink-axes", "--no-shrink",
                            "--no-encourage", "--no-collapse", "--encourage-limit", "--quiet", "--threads"})
        EXPECT_NE(m_stdout.find(opt), std::string::npos) << opt;
    EXPECT_NE(m_stdout.find("=1"), std::string::npos);  // defaults shown (support factor 1)
}

}  // namespace
