// End to end: prt-radii and prt-octree (from PRT_BIN_DIR) on pools made here with PointCloud +
// write_point_sections, and on the real kitten scan when ../shared/data is present.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "octree_check.h"
#include "point_cloud.h"
#include "prt/formats/pool.h"
#include "splat_test_data.h"

namespace {

namespace fs = std::filesystem;
using prt::pool::PoolFile;
using prt::pool::SectionType;

class SplatTools : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        m_dir = fs::temp_directory_path() /
                ("prt_splat_tools_" + std::to_string(::getpid()) + "_" + info->name());
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
    }

    /// True when the tool is built (prt-radii needs FLANN); the callers skip otherwise.
    static bool built(const char* tool) { return fs::exists(fs::path(PRT_BIN_DIR) / tool); }
    void TearDown() override { fs::remove_all(m_dir); }

    /// Runs a tool; returns its exit code, stderr in m_stderr.
    int run(const std::string& tool, const std::string& args) {
        const fs::path err = m_dir / "stderr.txt";
        const std::string cmd = (fs::path(PRT_BIN_DIR) / tool).string() + " " + args + " >" +
                                (m_dir / "stdout.txt").string() + " 2>" + err.string();
        const int status = std::system(cmd.c_str());
        std::ifstream in(err);
        std::stringstream ss;
        ss << in.rdbuf();
        m_stderr = ss.str();
        std::ifstream out_file(m_dir / "stdout.txt");
        std::stringstream so;
        so << out_file.rdbuf();
        m_stdout = so.str();
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }

    std::string path(const std::string& name) const { return (m_dir / name).string(); }

    void write_pool(const prt::pre::PointCloud& cloud, const std::string& name) {
        prt::pool::PoolWriter writer;
        prt::pre::write_point_sections(cloud, writer);
        writer.add_provenance("splat_tools_test", "0", "{}");
        writer.write(path(name));
    }

    fs::path m_dir;
    std::string m_stderr, m_stdout;
};

prt::pre::PointCloud sphere_cloud(std::size_t n) {
    const prt::test::SplatSet s = prt::test::sphere_points(n, 31, 2.0);
    prt::pre::PointCloud cloud;
    for (const auto& p : s.positions) cloud.positions.push_back({1e5 + p.x, 2e5 + p.y, -3e5 + p.z});
    cloud.normals = s.normals;
    return cloud;
}

/// The octree prt-octree wrote into `pool` (its info, nodes, leaf table and splats).
prt::pre::SplatOctree read_octree(const PoolFile& pool) {
    prt::pre::SplatOctree octree;
    octree.info = pool.array<prt::pool::OctreeInfo>(SectionType::octree_info)[0];
    const auto nodes = pool.array<std::uint32_t>(SectionType::octree_nodes);
    const auto leaves = pool.array<std::uint32_t>(SectionType::leaf_info);
    const auto splats = pool.array<prt::pool::Splat>(SectionType::splats);
    octree.nodes.assign(nodes.begin(), nodes.end());
    octree.leaf_info.assign(leaves.begin(), leaves.end());
    octree.splats.assign(splats.begin(), splats.end());
    return octree;
}

TEST_F(SplatTools, HelpDocumentsEveryOption) {
    if (!built("prt-radii")) GTEST_SKIP() << "prt-radii is not built (needs FLANN) in " << PRT_BIN_DIR;
    if (!built("prt-octree")) GTEST_SKIP() << "prt-octree is not built in " << PRT_BIN_DIR;
    ASSERT_EQ(run("prt-radii", "--help"), 0);
    for (const char* opt :
         {"--k", "--clamp-factor", "--threads", "--output", "--quiet", "--backend", "9", "3"})
        EXPECT_NE(m_stdout.find(opt), std::string::npos) << "prt-radii --help lacks " << opt;
    ASSERT_EQ(run("prt-octree", "--help"), 0);
    for (const char* opt : {"--leaf-size", "--max-depth", "--min-cell", "--no-replicate", "--threads",
                            "--output", "--quiet", "48", "24", "0.25"})
        EXPECT_NE(m_stdout.find(opt), std::string::npos) << "prt-octree --help lacks " << opt;
}

TEST_F(SplatTools, RadiiBackendsWriteTheSameRadiiOrCudaSaysWhyNot) {
    if (!built("prt-radii")) GTEST_SKIP() << "prt-radii is not built (needs FLANN) in " << PRT_BIN_DIR;
    write_pool(sphere_cloud(3000), "in.pool");
    ASSERT_EQ(run("prt-radii", path("in.pool") + " -o " + path("cpu.pool") + " --backend cpu"), 0)
        << m_stderr;
    const int rc = run("prt-radii", path("in.pool") + " -o " + path("cuda.pool") + " --backend cuda");
    if (rc != 0) {
        // no usable device here: one line saying why, and no output
        EXPECT_NE(m_stderr.find("--backend cuda: "), std::string::npos) << m_stderr;
        EXPECT_FALSE(std::filesystem::exists(path("cuda.pool")));
        return;
    }
    EXPECT_NE(m_stderr.find("time (cuda)"), std::string::npos) << m_stderr;
    const PoolFile a = PoolFile::open(path("cpu.pool")), b = PoolFile::open(path("cuda.pool"));
    const auto ra = a.array<float>(SectionType::radii), rb = b.array<float>(SectionType::radii);
    ASSERT_EQ(ra.size(), rb.size());
    EXPECT_EQ(std::memcmp(ra.data(), rb.data(), ra.size() * sizeof(float)), 0);
}

TEST_F(SplatTools, RadiiThenOctree) {
    if (!built("prt-radii")) GTEST_SKIP() << "prt-radii is not built (needs FLANN) in " << PRT_BIN_DIR;
    if (!built("prt-octree")) GTEST_SKIP() << "prt-octree is not built in " << PRT_BIN_DIR;
    write_pool(sphere_cloud(2000), "in.pool");
    ASSERT_EQ(run("prt-radii", path("in.pool") + " -o " + path("radii.pool")), 0) << m_stderr;
    EXPECT_NE(m_stderr.find("median"), std::string::npos) << m_stderr;  // statistics reported
    EXPECT_NE(m_stderr.find("clamped"), std::string::npos) << m_stderr;
    const PoolFile radii_pool = PoolFile::open(path("radii.pool"));
    const auto pos = radii_pool.array<prt::pool::Float3>(SectionType::positions);
    const auto nrm = radii_pool.array<prt::pool::Float3>(SectionType::normals);
    const auto rad = radii_pool.array<float>(SectionType::radii);
    ASSERT_EQ(rad.size(), 2000u);
    const std::vector<double> expected = prt::test::brute_force_knn({pos.begin(), pos.end()}, 9);
    std::size_t equal = 0;
    for (std::size_t i = 0; i < rad.size(); ++i)
        if (std::fabs(rad[i] - expected[i]) <= 1e-5 * expected[i]) ++equal;
    EXPECT_GE(equal, 1990u);  // all but the (rare) clamped outliers
    EXPECT_NE(radii_pool.provenance_json().find("prt-radii"), std::string::npos);

    ASSERT_EQ(run("prt-octree", path("radii.pool") + " -o " + path("octree.pool") + " --leaf-size 40"), 0)
        << m_stderr;
    EXPECT_NE(m_stderr.find("replication factor"), std::string::npos) << m_stderr;
    const PoolFile pool = PoolFile::open(path("octree.pool"));
    const prt::pre::SplatOctree octree = read_octree(pool);
    prt::pre::OctreeParams params;
    params.max_leaf_splats = 40;
    const auto p2 = pool.array<prt::pool::Float3>(SectionType::positions);
    const auto n2 = pool.array<prt::pool::Float3>(SectionType::normals);
    const auto r2 = pool.array<float>(SectionType::radii);
    prt::test::check_octree(octree, p2, n2, r2, params);
    const std::string prov = pool.provenance_json();
    EXPECT_NE(prov.find("prt-radii"), std::string::npos);
    EXPECT_NE(prov.find("prt-octree"), std::string::npos);

    // rerunning prt-radii drops the (now stale) octree
    ASSERT_EQ(run("prt-radii", path("octree.pool") + " -o " + path("again.pool") + " --k 5"), 0) << m_stderr;
    EXPECT_FALSE(PoolFile::open(path("again.pool")).has(SectionType::octree_nodes));
}

TEST_F(SplatTools, NoReplicateAndQuiet) {
    if (!built("prt-radii")) GTEST_SKIP() << "prt-radii is not built (needs FLANN) in " << PRT_BIN_DIR;
    if (!built("prt-octree")) GTEST_SKIP() << "prt-octree is not built in " << PRT_BIN_DIR;
    write_pool(sphere_cloud(1000), "in.pool");
    ASSERT_EQ(run("prt-radii", path("in.pool") + " -o " + path("radii.pool") + " --quiet"), 0);
    EXPECT_TRUE(m_stderr.empty()) << m_stderr;
    ASSERT_EQ(run("prt-octree", path("radii.pool") + " -o " + path("o.pool") + " --no-replicate -q"), 0);
    EXPECT_TRUE(m_stderr.empty()) << m_stderr;
    const PoolFile pool = PoolFile::open(path("o.pool"));
    const auto info = pool.array<prt::pool::OctreeInfo>(SectionType::octree_info)[0];
    EXPECT_EQ(info.splat_count, 1000u);
    EXPECT_EQ(info.flags & prt::pool::k_octree_replicated, 0u);
}

TEST_F(SplatTools, OctreeWithoutRadiiFailsCleanly) {
    if (!built("prt-octree")) GTEST_SKIP() << "prt-octree is not built in " << PRT_BIN_DIR;
    write_pool(sphere_cloud(200), "in.pool");
    EXPECT_EQ(run("prt-octree", path("in.pool") + " -o " + path("out.pool")), 1);
    EXPECT_NE(m_stderr.find("run prt-radii first"), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("in.pool"), std::string::npos) << m_stderr;
    EXPECT_EQ(std::count(m_stderr.begin(), m_stderr.end(), '\n'), 1) << m_stderr;  // one line
    EXPECT_FALSE(fs::exists(path("out.pool")));
}

TEST_F(SplatTools, OctreeWithoutNormalsFailsCleanly) {
    if (!built("prt-octree")) GTEST_SKIP() << "prt-octree is not built in " << PRT_BIN_DIR;
    prt::pre::PointCloud cloud = sphere_cloud(100);
    cloud.normals.clear();
    cloud.radii.assign(cloud.size(), 0.1f);
    write_pool(cloud, "in.pool");
    EXPECT_EQ(run("prt-octree", path("in.pool") + " -o " + path("out.pool")), 1);
    EXPECT_NE(m_stderr.find("normals"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(path("out.pool")));
}

TEST_F(SplatTools, OutputMayReplaceTheInput) {
    if (!built("prt-radii")) GTEST_SKIP() << "prt-radii is not built (needs FLANN) in " << PRT_BIN_DIR;
    if (!built("prt-octree")) GTEST_SKIP() << "prt-octree is not built in " << PRT_BIN_DIR;
    write_pool(sphere_cloud(500), "model.pool");
    ASSERT_EQ(run("prt-radii", path("model.pool") + " -o " + path("model.pool") + " -q"), 0) << m_stderr;
    ASSERT_EQ(run("prt-octree", path("model.pool") + " -o " + path("model.pool") + " -q -X 40"), 0)
        << m_stderr;
    const PoolFile pool = PoolFile::open(path("model.pool"));  // validated: checksums, cross-references
    EXPECT_EQ(pool.array<float>(SectionType::radii).size(), 500u);
    EXPECT_TRUE(pool.has(SectionType::splats));
}

TEST_F(SplatTools, BadInputAndUsage) {
    if (!built("prt-radii")) GTEST_SKIP() << "prt-radii is not built (needs FLANN) in " << PRT_BIN_DIR;
    if (!built("prt-octree")) GTEST_SKIP() << "prt-octree is not built in " << PRT_BIN_DIR;
    {
        std::ofstream junk(path("junk.pool"));
        junk << "not a pool";
    }
    EXPECT_EQ(run("prt-radii", path("junk.pool") + " -o " + path("out.pool")), 1);
    EXPECT_NE(m_stderr.find("junk.pool"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(path("out.pool")));
    write_pool(sphere_cloud(5), "tiny.pool");
    EXPECT_EQ(run("prt-radii", path("tiny.pool") + " -o " + path("out.pool")), 1);
    EXPECT_NE(m_stderr.find("lower --k"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(path("out.pool")));
    EXPECT_EQ(run("prt-octree", path("tiny.pool") + " -o " + path("out.pool") + " --max-depth 40"), 2);
    EXPECT_EQ(run("prt-radii", path("tiny.pool")), 2);  // -o missing
}

TEST_F(SplatTools, MissingInputAndUnwritableOutputAreOneLineBeforeTheWork) {
    if (!built("prt-octree")) GTEST_SKIP() << "prt-octree is not built in " << PRT_BIN_DIR;
    write_pool(sphere_cloud(500), "in.pool");
    for (const char* tool : {"prt-octree", "prt-radii", "prt-cull"}) {
        if (!built(tool)) continue;
        SCOPED_TRACE(tool);
        // A missing input: status 1, the tool's one line (not CLI11's usage wording, status 2).
        EXPECT_EQ(run(tool, path("none.pool") + " -o " + path("out.pool")), 1);
        EXPECT_EQ(m_stderr, std::string(tool) + ": error: " + path("none.pool") + ": no such file\n");
        // An output in a folder that does not exist, or a folder: refused before any work (one line).
        EXPECT_EQ(run(tool, path("in.pool") + " -o " + path("no/out.pool")), 1);
        EXPECT_EQ(m_stderr, std::string(tool) + ": error: " + path("no/out.pool") +
                                ": cannot write: folder " + path("no") + " does not exist\n");
        EXPECT_EQ(run(tool, path("in.pool") + " -o " + m_dir.string()), 1);
        EXPECT_NE(m_stderr.find("cannot write: it is a folder"), std::string::npos) << m_stderr;
        EXPECT_EQ(std::count(m_stderr.begin(), m_stderr.end(), '\n'), 1) << m_stderr;
    }
    EXPECT_FALSE(fs::exists(path("out.pool")));
}

TEST_F(SplatTools, RealKittenScan) {
    if (!built("prt-radii")) GTEST_SKIP() << "prt-radii is not built (needs FLANN) in " << PRT_BIN_DIR;
    if (!built("prt-octree")) GTEST_SKIP() << "prt-octree is not built in " << PRT_BIN_DIR;
    const fs::path file = fs::path(PRT_SHARED_DATA_DIR) / "points/cgal_kitten/kitten.xyz";
    if (!fs::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
    prt::pre::PointCloud cloud;
    std::ifstream in(file);
    double x, y, z, nx, ny, nz;
    while (in >> x >> y >> z >> nx >> ny >> nz) {
        cloud.positions.push_back({x, y, z});
        cloud.normals.push_back({float(nx), float(ny), float(nz)});
    }
    ASSERT_EQ(cloud.size(), 5210u);
    prt::pre::clean(cloud);
    write_pool(cloud, "kitten.pool");
    ASSERT_EQ(run("prt-radii", path("kitten.pool") + " -o " + path("r.pool")), 0) << m_stderr;
    std::cout << m_stderr;  // the statistics of a real scan, for the test log
    ASSERT_EQ(run("prt-octree", path("r.pool") + " -o " + path("o.pool") + " -X 48"), 0) << m_stderr;
    std::cout << m_stderr;
    const PoolFile pool = PoolFile::open(path("o.pool"));
    const prt::pre::SplatOctree octree = read_octree(pool);
    prt::pre::OctreeParams kitten_params;
    kitten_params.max_leaf_splats = 48;
    const auto summary =
        prt::test::check_octree(octree, pool.array<prt::pool::Float3>(SectionType::positions),
                                pool.array<prt::pool::Float3>(SectionType::normals),
                                pool.array<float>(SectionType::radii), kitten_params);
    EXPECT_GT(summary.leaves.size(), 100u);
}

}  // namespace
