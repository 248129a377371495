// prt-patches end to end (PRT_BIN_DIR/prt-patches): exit codes 0 / 1 (bad file) / 2 (bad usage),
// one-line errors naming file and line, no output (and an existing output untouched) on failure,
// --quiet, --help, and the pool it writes.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "patch_pool.h"
#include "prt/formats/pool.h"
#include "prt/runtime/surface_pools.h"
#include "runtime/tool_fixture.h"

namespace {

namespace fs = std::filesystem;

class PatchTool : public prt::test::ToolTest {
protected:
    PatchTool() : ToolTest("prt-patches", "prt_patch_tool_") {}
    std::string write(const std::string& name, const std::string& text) {
        std::ofstream(m_dir / name) << text;
        return (m_dir / name).string();
    }
};

/// One flat patch in .bpt form, z = 0 over [0,3]^2.
std::string flat_bpt() {
    std::string s = "1\n3 3\n";
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) s += std::to_string(i) + " " + std::to_string(j) + " 0\n";
    return s;
}

TEST_F(PatchTool, WritesAValidPool) {
    const std::string in = write("flat.bpt", flat_bpt());
    ASSERT_EQ(run(in + " -o " + path("flat.pool") + " --depth 3"), 0) << m_stderr;
    const auto pool = prt::pool::PoolFile::open(path("flat.pool"));
    const auto view = prt::rt::load_patch_view(pool);
    EXPECT_EQ(view.patch_count, 1u);
    EXPECT_EQ(view.subpatch_depth, 3u);
    EXPECT_NE(pool.provenance_json().find("\"prt-patches\""), std::string::npos);
    EXPECT_NE(pool.provenance_json().find("\"depth\":3"), std::string::npos);
    EXPECT_NE(m_stderr.find("1 patches"), std::string::npos);  // statistics on stderr
    EXPECT_EQ(m_stdout, "");
    ASSERT_EQ(run(in + " -o " + path("quiet.pool") + " --quiet"), 0);
    EXPECT_EQ(m_stderr, "");
}

TEST_F(PatchTool, BadFileFailsWithOneLineAndWritesNothing) {
    std::string bad = flat_bpt();
    bad.replace(bad.find("2 1 0"), 5, "2 nan 0");
    const std::string in = write("bad.bpt", bad);
    // an existing output stays as it was
    write("keep.pool", "previous contents");
    EXPECT_EQ(run(in + " -o " + path("keep.pool")), 1);
    EXPECT_EQ(m_stderr,
              "prt-patches: error: " + in + ":12: patch 1 control point 10: 'nan' is not a finite number\n");
    EXPECT_EQ(prt::test::slurp(path("keep.pool")), "previous contents");
    EXPECT_EQ(run(in + " -o " + path("new.pool")), 1);
    EXPECT_FALSE(fs::exists(path("new.pool")));
    for (const auto& e : fs::directory_iterator(m_dir))
        EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << "temporary file left: " << e.path();
    // missing input
    EXPECT_EQ(run(path("absent.bpt") + " -o " + path("x.pool")), 1);
    EXPECT_EQ(m_stderr.rfind("prt-patches: error: " + path("absent.bpt") + ": cannot open", 0), 0u)
        << m_stderr;
    // output folder missing
    EXPECT_EQ(run(in + " -o " + path("no/such/dir/x.pool")), 1);
    EXPECT_NE(m_stderr.find("does not exist"), std::string::npos);
}

TEST_F(PatchTool, UsageErrorsExitTwo) {
    const std::string in = write("flat.bpt", flat_bpt());
    EXPECT_EQ(run(in), 2);  // no -o
    EXPECT_EQ(run(in + " -o " + path("x.pool") + " --depth 11"), 2);
    EXPECT_EQ(run(in + " -o " + path("x.pool") + " --format obj"), 2);
    EXPECT_EQ(run(in + " -o " + path("x.pool") + " --orient sideways"), 2);
    EXPECT_EQ(std::count(m_stderr.begin(), m_stderr.end(), '\n'), 1) << m_stderr;
}

TEST_F(PatchTool, HelpDocumentsEveryOptionWithItsDefault) {
    ASSERT_EQ(run("--help"), 0);
    for (const char* text : {"--output", "--format", "auto", "--depth", "6", "--bins", "16", "--orient",
                             "outward", "--quiet", "seed 002"})
        EXPECT_NE(m_stdout.find(text), std::string::npos) << text;
}

TEST_F(PatchTool, SharedTeapotBuildsOriented) {
    const std::string teapot = std::string(PRT_SHARED_DATA_DIR) + "/bezier/teapot";
    if (!fs::exists(teapot)) GTEST_SKIP() << "shared data not found: " << teapot;
    ASSERT_EQ(run(teapot + " -o " + path("teapot.pool")), 0) << m_stderr;
    const auto pool = prt::pool::PoolFile::open(path("teapot.pool"));
    const auto view = prt::rt::load_patch_view(pool);
    EXPECT_EQ(view.patch_count, 32u);
    EXPECT_EQ(view.subpatch_nodes, 127u);
    EXPECT_TRUE(view.flags & prt::pool::k_patch_oriented);
    EXPECT_NE(m_stderr.find("0 conflicts"), std::string::npos) << m_stderr;
    ASSERT_EQ(run(teapot + " -o " + path("raw.pool") + " --orient none"), 0);
    EXPECT_FALSE(prt::rt::load_patch_view(prt::pool::PoolFile::open(path("raw.pool"))).flags &
                 prt::pool::k_patch_oriented);
}

}  // namespace
