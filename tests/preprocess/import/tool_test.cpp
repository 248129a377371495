// prt-import end to end (PRT_BIN_DIR/prt-import): exit codes 0 / 1 (bad file) / 2 (bad usage), no
// output left behind on failure, a valid pool on success, --help documenting every option.
#include <sys/wait.h>

#include <cstdlib>
#include <sstream>

#include "import_test_util.h"
#include "point_cloud.h"
#include "prt/formats/pool.h"

namespace {

using namespace prt_import_test;

class ToolTest : public TempDirTest {
protected:
    void SetUp() override {
        TempDirTest::SetUp();
        m_tool = fs::path(PRT_BIN_DIR) / "prt-import";
        if (!fs::exists(m_tool)) GTEST_SKIP() << "prt-import is not built in " << PRT_BIN_DIR;
    }

    int run(const std::string& args) {
        const std::string cmd =
            m_tool.string() + " " + args + " >" + path("out.txt").string() + " 2>" + path("err.txt").string();
        const int status = std::system(cmd.c_str());
        auto slurp = [](const fs::path& p) {
            std::ifstream in(p);
            std::stringstream ss;
            ss << in.rdbuf();
            return ss.str();
        };
        m_stdout = slurp(path("out.txt"));
        m_stderr = slurp(path("err.txt"));
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }

    /// Files in the folder other than the captured output: what a failed run must not leave.
    std::vector<std::string> leftovers(const std::vector<std::string>& inputs) const {
        std::vector<std::string> out;
        for (const auto& e : fs::directory_iterator(m_dir)) {
            const std::string name = e.path().filename().string();
            if (name == "out.txt" || name == "err.txt") continue;
            if (std::find(inputs.begin(), inputs.end(), name) != inputs.end()) continue;
            out.push_back(name);
        }
        return out;
    }

    fs::path m_tool;
    std::string m_stdout, m_stderr;
};

TEST_F(ToolTest, ImportsAPlyIntoAValidPool) {
    write("in.ply",
          "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
          "property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nproperty uchar "
          "green\nproperty uchar blue\nproperty float extra\nend_header\n"
          "1 2 3 0 0 1 10 20 30 9\n4 5 6 0 1 0 40 50 60 9\n7 8 9 1 0 0 70 80 90 9\n");
    ASSERT_EQ(run(path("in.ply").string() + " -o " + path("out.pool").string()), 0) << m_stderr;
    const auto pool = prt::pool::PoolFile::open(path("out.pool"));
    const auto cloud = prt::pre::read_point_sections(pool);
    ASSERT_EQ(cloud.size(), 3u);
    EXPECT_NEAR(cloud.positions[2][2], 9.0, 1e-6);
    EXPECT_EQ(cloud.colors[1].g, 50);
    EXPECT_FLOAT_EQ(cloud.normals[1].y, 1.f);
    const std::string provenance = pool.provenance_json();
    EXPECT_NE(provenance.find("prt-import"), std::string::npos) << provenance;
    EXPECT_NE(provenance.find("\"k\":16"), std::string::npos) << provenance;
    EXPECT_NE(m_stderr.find("skipped vertex properties: extra"), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("3 points read, 3 kept"), std::string::npos) << m_stderr;

    // --quiet: nothing on stderr.
    ASSERT_EQ(run("--quiet " + path("in.ply").string() + " -o " + path("q.pool").string()), 0);
    EXPECT_EQ(m_stderr, "");
}

TEST_F(ToolTest, BadFileExitsOneWithOneLineAndNoOutput) {
    write("bad.ply",
          "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float "
          "z\nend_header\n1 2 3\n");
    EXPECT_EQ(run(path("bad.ply").string() + " -o " + path("out.pool").string()), 1);
    EXPECT_EQ(std::count(m_stderr.begin(), m_stderr.end(), '\n'), 1) << m_stderr;
    EXPECT_NE(m_stderr.find("prt-import: error: " + path("bad.ply").string() +
                            ": header declares 4 vertices but the "
                            "data ends after 1"),
              std::string::npos)
        << m_stderr;
    EXPECT_TRUE(leftovers({"bad.ply"}).empty()) << ::testing::PrintToString(leftovers({"bad.ply"}));

    EXPECT_EQ(run(path("missing.xyz").string() + " -o " + path("out.pool").string()), 1);
    EXPECT_NE(m_stderr.find("missing.xyz: cannot open"), std::string::npos) << m_stderr;
    write("empty.xyz", "");
    EXPECT_EQ(run(path("empty.xyz").string() + " -o " + path("out.pool").string()), 1);
    EXPECT_NE(m_stderr.find("empty.xyz: file is empty"), std::string::npos) << m_stderr;
    EXPECT_TRUE(leftovers({"bad.ply", "empty.xyz"}).empty());
}

TEST_F(ToolTest, BadUsageExitsTwo) {
    write("in.xyz", "0 0 0 0 0 1\n");
    EXPECT_EQ(run(path("in.xyz").string()), 2);  // no -o
    EXPECT_EQ(run(path("in.xyz").string() + " -o " + path("o.pool").string() + " --format banana"), 2);
    EXPECT_EQ(run(path("in.xyz").string() + " -o " + path("o.pool").string() + " --k 1"), 2);
    EXPECT_EQ(run(path("in.xyz").string() + " -o " + path("o.pool").string() + " --sensor 1,2"), 2);
    EXPECT_EQ(run(path("in.xyz").string() + " -o " + path("o.pool").string() + " --no-such-option"), 2);
    EXPECT_TRUE(leftovers({"in.xyz"}).empty());
}

TEST_F(ToolTest, HelpDocumentsEveryOption) {
    ASSERT_EQ(run("--help"), 0);
    for (const char* opt : {"--output", "--format", "--normals", "--mesh-mode", "--sample", "--seed",
                            "--sample-normals", "--k", "--sensor", "--keep-duplicates", "--quiet"})
        EXPECT_NE(m_stdout.find(opt), std::string::npos) << opt << " missing from --help";
    // defaults shown
    EXPECT_NE(m_stdout.find("16"), std::string::npos);
}

TEST_F(ToolTest, EstimatesNormalsEndToEnd) {
    if (!prt::pre::import::have_pcl()) GTEST_SKIP() << "this build has no PCL";
    std::string text;
    for (int i = 0; i < 30; ++i)
        for (int j = 0; j < 30; ++j) text += std::to_string(i * 0.1) + " " + std::to_string(j * 0.1) + " 0\n";
    write("plane.xyz", text);
    ASSERT_EQ(run(path("plane.xyz").string() + " -o " + path("p.pool").string() + " --sensor 0,0,10 --k 8"),
              0)
        << m_stderr;
    const auto pool = prt::pool::PoolFile::open(path("p.pool"));
    EXPECT_TRUE(pool.model_info().flags & prt::pool::k_model_normals_estimated);
    const auto cloud = prt::pre::read_point_sections(pool);
    for (const auto& n : cloud.normals) ASSERT_GT(n.z, 0.99f);
    EXPECT_NE(m_stderr.find("oriented toward the sensor"), std::string::npos) << m_stderr;
}

}  // namespace
