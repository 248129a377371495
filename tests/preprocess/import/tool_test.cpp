// prt-import end to end (PRT_BIN_DIR/prt-import): exit codes 0 / 1 (bad file) / 2 (bad usage), no
// output left behind on failure, a valid pool on success, --help documenting every option.
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
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
    EXPECT_NE(provenance.find("\"k\":24"), std::string::npos) << provenance;
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
    EXPECT_EQ(run("-o " + path("o.pool").string()), 2);  // no input and no --poses
    EXPECT_EQ(run(path("in.xyz").string() + " " + path("in.xyz").string() + " -o " + path("o.pool").string()),
              2);
    EXPECT_NE(m_stderr.find("several inputs need --poses"), std::string::npos) << m_stderr;
    EXPECT_EQ(run(path("in.xyz").string() + " -o " + path("o.pool").string() + " --sensor 1,2,3 --no-sensor"),
              2);
    EXPECT_EQ(run(path("in.xyz").string() + " -o " + path("o.pool").string() +
                  " --sensor 1,2,3 --sensor-direction 0,0,1"),
              2);
    EXPECT_EQ(run(path("in.xyz").string() + " -o " + path("o.pool").string() +
                  " --outlier-k 4 --outlier-min-neighbours 5"),
              2);
    EXPECT_TRUE(leftovers({"in.xyz"}).empty());
}

TEST_F(ToolTest, HelpDocumentsEveryOption) {
    ASSERT_EQ(run("--help"), 0);
    for (const char* opt : {"--output",
                            "--format",
                            "--normals",
                            "--mesh-mode",
                            "--sample",
                            "--seed",
                            "--sample-normals",
                            "--k",
                            "--sensor",
                            "--sensor-direction",
                            "--no-sensor",
                            "--grazing-cos",
                            "--poses",
                            "--keep-outliers",
                            "--outlier-k",
                            "--outlier-std",
                            "--outlier-radius",
                            "--outlier-min-neighbours",
                            "--keep-duplicates",
                            "--keep-fraction",
                            "--quiet"})
        EXPECT_NE(m_stdout.find(opt), std::string::npos) << opt << " missing from --help";
    // defaults shown
    EXPECT_NE(m_stdout.find("=24"), std::string::npos);
}

TEST_F(ToolTest, EstimatesNormalsEndToEnd) {
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

std::string xyz_grid(double z0, int n, double step) {
    std::string text;
    char buf[96];
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double x = i * step, y = j * step;
            std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g\n", x, y,
                          z0 + 0.02 * std::sin(7 * x) * std::cos(5 * y));
            text += buf;
        }
    return text;
}

TEST_F(ToolTest, MergesScansOfAPoseList) {
    write("a.xyz", xyz_grid(0, 40, 0.025));
    write("b.xyz", xyz_grid(0, 40, 0.025));
    // b is the same patch moved by +1 in x; a's scanner above, b's far away below.
    write("poses.json", R"({"scans": [
        {"file": "a.xyz", "sensor": {"point": [0.5, 0.5, 5]}},
        {"file": "b.xyz", "translation": [1, 0, 0], "quaternion": {"w": 1, "x": 0, "y": 0, "z": 0},
         "sensor": {"direction": [0, 0, -1]}}]})");
    ASSERT_EQ(run("--poses " + path("poses.json").string() + " -o " + path("m.pool").string()), 0)
        << m_stderr;
    const auto pool = prt::pool::PoolFile::open(path("m.pool"));
    const auto cloud = prt::pre::read_point_sections(pool);
    ASSERT_EQ(cloud.sensors.size(), 2u);
    ASSERT_EQ(cloud.scan_ids.size(), cloud.size());
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const bool b = cloud.scan_ids[i] == 1;
        wrong += b != (cloud.positions[i][0] > 0.99);
        wrong += b ? cloud.normals[i].z > -0.9f : cloud.normals[i].z < 0.9f;
    }
    EXPECT_EQ(wrong, 0u);
    EXPECT_NE(m_stderr.find("a.xyz: read xyz"), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("b.xyz: outliers: "), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("merged 2 scans: 3200 points read"), std::string::npos) << m_stderr;
    EXPECT_NE(m_stderr.find("sensors: 2 (one per scan)"), std::string::npos) << m_stderr;
    EXPECT_NE(pool.provenance_json().find("poses.json"), std::string::npos);

    // Bad pose lists: one line naming the pose file and the entry, exit 1, nothing written.
    write("shear.json", R"({"scans": [{"file": "a.xyz"},
        {"file": "b.xyz", "matrix": [1, 0.5, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}]})");
    EXPECT_EQ(run("--poses " + path("shear.json").string() + " -o " + path("bad.pool").string()), 1);
    EXPECT_EQ(m_stderr.rfind(
                  "prt-import: error: " + path("shear.json").string() + ": scans[1]: matrix is not rigid", 0),
              0u)
        << m_stderr;
    EXPECT_EQ(std::count(m_stderr.begin(), m_stderr.end(), '\n'), 1);
    write("short.conf", "bmesh a.xyz 0 0 0 0 0 1\n");
    EXPECT_EQ(run("--poses " + path("short.conf").string() + " -o " + path("bad.pool").string()), 1);
    EXPECT_NE(m_stderr.find("short.conf: line 1: bmesh needs"), std::string::npos) << m_stderr;
    write("nan.conf", "bmesh a.xyz 0 0 nan 0 0 0 1\n");
    EXPECT_EQ(run("--poses " + path("nan.conf").string() + " -o " + path("bad.pool").string()), 1);
    EXPECT_NE(m_stderr.find("nan.conf: line 1: tz 'nan' is not finite"), std::string::npos) << m_stderr;
    EXPECT_TRUE(leftovers({"a.xyz", "b.xyz", "poses.json", "m.pool", "shear.json", "short.conf", "nan.conf"})
                    .empty());
}

TEST_F(ToolTest, OutliersRemovedByDefaultKeptOnRequest) {
    std::string text = xyz_grid(0, 40, 0.025);
    text += "0.5 0.5 0.4\n0.2 0.7 -0.3\n0.9 0.1 0.25\n";  // far off the patch
    write("scan.xyz", text);
    ASSERT_EQ(run(path("scan.xyz").string() + " -o " + path("o.pool").string()), 0) << m_stderr;
    EXPECT_EQ(prt::pool::PoolFile::open(path("o.pool")).model_info().point_count, 1600u);
    EXPECT_NE(m_stderr.find("outliers: removed 3 of 1603 points"), std::string::npos) << m_stderr;
    ASSERT_EQ(run(path("scan.xyz").string() + " -o " + path("k.pool").string() + " --keep-outliers"), 0)
        << m_stderr;
    EXPECT_EQ(prt::pool::PoolFile::open(path("k.pool")).model_info().point_count, 1603u);
    EXPECT_NE(m_stderr.find("outliers: not run (--keep-outliers)"), std::string::npos) << m_stderr;
}

TEST_F(ToolTest, ColoursOfTheWrongTypeWriteNothing) {
    write("c.ply",
          "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
          "property float red\nproperty float green\nproperty float blue\nend_header\n"
          "0 0 0 0.5 0.5 0.5\n1 0 0 0.5 255 0.5\n");
    EXPECT_EQ(run(path("c.ply").string() + " -o " + path("c.pool").string()), 1);
    EXPECT_EQ(m_stderr, "prt-import: error: " + path("c.ply").string() +
                            ": vertex 1: green = 255 is outside 0..1 (a float colour)\n");
    EXPECT_TRUE(leftovers({"c.ply"}).empty());
}

// A pool in (prt-synth's scans: sensors, no normals): its provenance comes first, its sensors stay,
// normals are estimated and face them; stale sections (radii) are not carried over.
TEST_F(ToolTest, PoolInputKeepsProvenanceAndSensors) {
    prt::pre::PointCloud in;
    for (int i = 0; i < 40; ++i)
        for (int j = 0; j < 40; ++j) {
            const double x = i * 0.025, y = j * 0.025;
            in.positions.push_back({x, y, 0.02 * std::sin(7 * x) * std::cos(5 * y)});
            in.intensities.push_back(static_cast<float>(i));
            in.radii.push_back(0.01f);
            in.scan_ids.push_back(static_cast<std::uint16_t>(x < 0.5 ? 0 : 1));
        }
    in.sensors = {prt::pool::Sensor{{0.2, 0.5, 3}, prt::pool::k_sensor_point, 0},
                  prt::pool::Sensor{{0, 0, -1}, prt::pool::k_sensor_direction, 0}};
    in.flags = prt::pool::k_model_synthetic;
    {
        prt::pool::PoolWriter w;
        prt::pre::write_point_sections(in, w);
        w.add_provenance("prt-synth", "test", R"({"shape": {"kind": "plane", "size": 1}})");
        w.write(path("scan.pool"));
    }
    ASSERT_EQ(run(path("scan.pool").string() + " -o " + path("out.pool").string()), 0) << m_stderr;
    const auto pool = prt::pool::PoolFile::open(path("out.pool"));
    const std::string prov = pool.provenance_json();
    const auto synth = prov.find("\"prt-synth\""), import = prov.find("\"prt-import\"");
    ASSERT_NE(synth, std::string::npos) << prov;
    ASSERT_NE(import, std::string::npos) << prov;
    EXPECT_LT(synth, import) << prov;
    EXPECT_NE(prov.find("\"kind\":\"plane\""), std::string::npos) << prov;
    EXPECT_TRUE(pool.model_info().flags & prt::pool::k_model_synthetic);
    EXPECT_TRUE(pool.model_info().flags & prt::pool::k_model_normals_estimated);
    const auto out = prt::pre::read_point_sections(pool);
    ASSERT_EQ(out.sensors.size(), 2u);
    ASSERT_EQ(out.scan_ids.size(), out.size());
    ASSERT_EQ(out.size(), 1600u);
    EXPECT_FALSE(out.has_radii());
    ASSERT_TRUE(out.has_intensities());
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < out.size(); ++i) {
        wrong += out.scan_ids[i] != (out.positions[i][0] < 0.5 ? 0 : 1);
        wrong += out.intensities[i] != std::round(out.positions[i][0] / 0.025);
        wrong += out.scan_ids[i] == 0 ? out.normals[i].z < 0.9f : out.normals[i].z > -0.9f;
    }
    EXPECT_EQ(wrong, 0u);
    EXPECT_NE(m_stderr.find("not carried over: radii"), std::string::npos) << m_stderr;

    // --normals estimate on a pool that has normals re-estimates them; auto keeps them.
    ASSERT_EQ(run(path("out.pool").string() + " -o " + path("again.pool").string() + " --no-sensor"), 0)
        << m_stderr;
    EXPECT_NE(m_stderr.find("normals: from the file"), std::string::npos) << m_stderr;
    ASSERT_EQ(run(path("out.pool").string() + " -o " + path("again.pool").string() +
                  " --no-sensor --normals estimate"),
              0)
        << m_stderr;
    const auto again = prt::pre::read_point_sections(prt::pool::PoolFile::open(path("again.pool")));
    EXPECT_TRUE(again.sensors.empty());
    for (const auto& n : again.normals) ASSERT_GT(n.z, 0.9f);  // propagation, seeded +z
}

}  // namespace

namespace {
using ToolTestKeep = ToolTest;
}

TEST_F(ToolTestKeep, KeepFractionDecimatesTheSamePointsForTheSameSeed) {
    std::ostringstream xyz;
    for (int i = 0; i < 100; ++i)
        for (int j = 0; j < 100; ++j) xyz << 0.01 * i << " " << 0.01 * j << " 0 0 0 1\n";
    write("grid.xyz", xyz.str());
    auto points = [&](const std::string& name) {
        const prt::pool::PoolFile p = prt::pool::PoolFile::open(path(name));
        return prt::pre::read_point_sections(p).positions;
    };
    ASSERT_EQ(run(path("grid.xyz").string() + " --keep-fraction 0.25 -o " + path("a.pool").string()), 0)
        << m_stderr;
    EXPECT_NE(m_stderr.find("decimated: dropped"), std::string::npos) << m_stderr;
    ASSERT_EQ(run(path("grid.xyz").string() + " --keep-fraction 0.25 -o " + path("b.pool").string()), 0);
    ASSERT_EQ(run(path("grid.xyz").string() + " --keep-fraction 0.25 --seed 7 -o " + path("c.pool").string()),
              0);
    const auto a = points("a.pool"), b = points("b.pool"), c = points("c.pool");
    EXPECT_NEAR(double(a.size()), 2500.0, 150.0);  // binomial: sd 43
    EXPECT_EQ(a, b);
    EXPECT_NE(a, c);
    EXPECT_EQ(run(path("grid.xyz").string() + " --keep-fraction 0 -o " + path("d.pool").string()), 2);
}
