// prt-import out of core (issue 17, --memory): import_file_out_of_core against the in-core
// import_file on synthetic PLY and XYZ scans (written here), with tiles and memory forced small:
// the pools both write are compared section by section, byte for byte, and the counts of the
// reports. The in-core path is itself checked against analytic references elsewhere (normals_test,
// ply_reader_test, ...); here it is the reference. Also: the one-line errors of what is not out of
// core, the median selection against nth_element, and the tool end to end (--tile-points).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <sstream>

#include "import_test_util.h"
#include "out_of_core.h"
#include "prt/error.h"
#include "prt/formats/pool.h"

namespace {

using namespace prt::pre::import;
using namespace prt_import_test;
using prt::pool::Float3;

struct Scan {
    std::vector<std::array<double, 3>> positions;
    std::vector<Float3> normals;
    std::vector<std::array<std::uint8_t, 3>> colors;
    std::vector<float> intensities;
};

/// A scan-like set far from the origin: a wavy ground denser near the scanner, a sphere, a few
/// far outliers, exact duplicates, non-finite points and (with normals) a few zero normals.
Scan synthetic_scan(bool with_normals, int ground = 3000) {
    Scan s;
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double ox = 4.5e5, oy = 5.2e6, oz = 120.0;
    auto add = [&](std::array<double, 3> p, Float3 n) {
        s.positions.push_back(p);
        s.normals.push_back(n);
        s.colors.push_back({std::uint8_t(rng() & 255), std::uint8_t(rng() & 255), std::uint8_t(rng() & 255)});
        s.intensities.push_back(float(u(rng)));
    };
    for (int i = 0; i < ground; ++i) {
        const double r = 20.0 * u(rng) * u(rng) + 0.5, t = 1.5707963 * u(rng);
        const double x = r * std::cos(t), y = r * std::sin(t);
        add({ox + x, oy + y, oz + 0.2 * std::sin(x) * std::cos(0.5 * y)}, {0.f, 0.f, 1.f});
    }
    for (int i = 0; i < 1200; ++i) {
        const double z = 2 * u(rng) - 1, t = 6.2831853 * u(rng), c = std::sqrt(1 - z * z);
        add({ox + 8 + c * std::cos(t), oy + 8 + c * std::sin(t), oz + 2 + z},
            {float(c * std::cos(t)), float(c * std::sin(t)), float(z)});
    }
    for (int i = 0; i < 12; ++i)  // isolated points far off the surfaces
        add({ox + 30 + 7 * u(rng), oy - 20 + 9 * u(rng), oz + 15 + 5 * u(rng)}, {1.f, 0.f, 0.f});
    const std::size_t n = s.positions.size();
    for (int i = 0; i < 40; ++i) {  // exact duplicates (later in the file)
        const std::size_t j = std::size_t(i) * 97 % n;
        add(s.positions[j], s.normals[j]);
    }
    const double nan = std::nan("");
    add({nan, oy, oz}, {0.f, 0.f, 1.f});
    add({ox, std::numeric_limits<double>::infinity(), oz}, {0.f, 0.f, 1.f});
    if (with_normals) {
        add({ox + 1, oy + 1, oz + 0.5}, {0.f, 0.f, 0.f});
        add({ox + 2, oy + 1, oz + 0.5}, {nan, 0.f, 1.f});
    }
    // Shuffle so duplicates and bad points are spread over the chunks.
    std::vector<std::size_t> order(s.positions.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::shuffle(order.begin(), order.end(), rng);
    Scan out;
    for (const std::size_t i : order) {
        out.positions.push_back(s.positions[i]);
        out.normals.push_back(s.normals[i]);
        out.colors.push_back(s.colors[i]);
        out.intensities.push_back(s.intensities[i]);
    }
    if (!with_normals) out.normals.clear();
    return out;
}

/// Binary little-endian PLY: double x y z, [float nx ny nz], uchar rgb, float intensity, and a
/// camera element (the scanner) when `camera` is given.
std::string ply_bytes(const Scan& s, const std::array<double, 3>* camera) {
    std::string h = "ply\nformat binary_little_endian 1.0\nelement vertex " +
                    std::to_string(s.positions.size()) +
                    "\nproperty double x\nproperty double y\nproperty double z\n";
    if (!s.normals.empty()) h += "property float nx\nproperty float ny\nproperty float nz\n";
    h += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float intensity\n";
    if (camera)
        h += "element camera 1\nproperty float view_px\nproperty float view_py\nproperty float view_pz\n";
    h += "end_header\n";
    for (std::size_t i = 0; i < s.positions.size(); ++i) {
        for (int a = 0; a < 3; ++a) put(h, s.positions[i][a]);
        if (!s.normals.empty()) {
            put(h, s.normals[i].x);
            put(h, s.normals[i].y);
            put(h, s.normals[i].z);
        }
        for (int a = 0; a < 3; ++a) put(h, s.colors[i][a]);
        put(h, s.intensities[i]);
    }
    if (camera)
        for (int a = 0; a < 3; ++a) put(h, float((*camera)[a]));
    return h;
}

std::string xyz_bytes(const Scan& s) {
    std::string t = "# synthetic scan\n";
    char buf[256];
    for (std::size_t i = 0; i < s.positions.size(); ++i) {
        const auto& p = s.positions[i];
        if (s.normals.empty())
            std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g\n", p[0], p[1], p[2]);
        else
            std::snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g,%.9g,%.9g,%.9g\n", p[0], p[1], p[2],
                          double(s.normals[i].x), double(s.normals[i].y), double(s.normals[i].z));
        t += buf;
        if (i % 500 == 7) t += "1 2\n";  // malformed lines, dropped and counted
    }
    return t;
}

class ImportOutOfCore : public TempDirTest {
protected:
    /// Imports `file` in core and out of core (tiles of `tile` points, `memory` bytes) and expects
    /// the same pool sections byte for byte and the same counts.
    void expect_equal(const fs::path& file, Options options, std::uint64_t tile, std::uint64_t memory) {
        SCOPED_TRACE(file.filename().string() + ", tile " + std::to_string(tile) + ", memory " +
                     std::to_string(memory));
        options.quiet = true;
        Report in_report, out_report;
        const prt::pre::PointCloud cloud = import_file(file, options, in_report);
        prt::pool::PoolWriter in_writer;
        prt::pre::write_point_sections(cloud, in_writer);
        MemoryParams mem;
        mem.memory = memory;
        mem.tile_points = tile;
        mem.spill_folder = m_dir;
        const SpilledCloud spilled = import_file_out_of_core(file, options, mem, out_report);
        prt::pool::PoolWriter out_writer;
        write_point_sections(spilled, mem, out_writer);
        const std::vector<std::byte> a = in_writer.serialize(), b = out_writer.serialize();
        const prt::pool::PoolFile pa = prt::pool::PoolFile::from_bytes(a, "in core");
        const prt::pool::PoolFile pb = prt::pool::PoolFile::from_bytes(b, "out of core");
        ASSERT_EQ(pa.sections().size(), pb.sections().size());
        for (std::size_t i = 0; i < pa.sections().size(); ++i) {
            const auto& ea = pa.sections()[i];
            const auto& eb = pb.sections()[i];
            SCOPED_TRACE("section " + std::string(ea.name, strnlen(ea.name, sizeof ea.name)));
            EXPECT_EQ(ea.type, eb.type);
            EXPECT_EQ(ea.count, eb.count);
            const auto sa = pa.bytes(ea);
            const auto sb = pb.bytes(eb);
            ASSERT_EQ(sa.size(), sb.size());
            EXPECT_TRUE(std::equal(sa.begin(), sa.end(), sb.begin()));
        }
        EXPECT_EQ(a, b);
        EXPECT_EQ(spilled.size, cloud.size());
        EXPECT_EQ(in_report.records, out_report.records);
        EXPECT_EQ(in_report.malformed_lines, out_report.malformed_lines);
        EXPECT_EQ(in_report.clean.summary(), out_report.clean.summary());
        EXPECT_EQ(in_report.outliers.removed, out_report.outliers.removed);
        EXPECT_EQ(in_report.outliers.statistical, out_report.outliers.statistical);
        EXPECT_EQ(in_report.outliers.radius, out_report.outliers.radius);
        EXPECT_EQ(in_report.outliers.threshold, out_report.outliers.threshold);
        EXPECT_EQ(in_report.outliers.median_spacing, out_report.outliers.median_spacing);
        EXPECT_EQ(in_report.outliers.range_scaled, out_report.outliers.range_scaled);
        EXPECT_EQ(in_report.estimate_failed, out_report.estimate_failed);
        EXPECT_EQ(in_report.ambiguous, out_report.ambiguous);
        EXPECT_EQ(in_report.grazing_flipped, out_report.grazing_flipped);
        EXPECT_EQ(in_report.decimated, out_report.decimated);
        EXPECT_EQ(in_report.sensors_detail, out_report.sensors_detail);
        EXPECT_EQ(in_report.written, out_report.written);
        m_last = in_report;
    }
    Report m_last;
};

const std::array<double, 3> k_scanner = {4.5e5 - 1.0, 5.2e6 - 1.0, 121.5};

TEST_F(ImportOutOfCore, PlyWithCameraEstimatedNormalsEqualsInCore) {
    const auto file = write("scan.ply", ply_bytes(synthetic_scan(false), &k_scanner));
    Options options;
    options.grazing_cos = 0;  // orientation by the sensor alone: out of core
    for (const std::uint64_t tile : {150u, 1000u}) expect_equal(file, options, tile, 200000);
    expect_equal(file, options, 700, std::uint64_t(1) << 30);
    // The fixture exercises what it should (in-core counts).
    EXPECT_GT(m_last.clean.duplicates, 0u);
    EXPECT_GT(m_last.clean.non_finite, 0u);
    EXPECT_GT(m_last.outliers.removed, 0u);
    EXPECT_TRUE(m_last.outliers.range_scaled);
    EXPECT_TRUE(m_last.oriented_to_sensor);
    // The grazing normals take their sign from the others over the k-NN graph (the default).
    for (const double grazing : {0.3, 0.8}) {
        options.grazing_cos = grazing;
        expect_equal(file, options, 150, std::uint64_t(16) << 20);  // the grazing edges: ~3 MB at 0.8
        expect_equal(file, options, 1000, std::uint64_t(1) << 30);
        EXPECT_NE(m_last.normals_detail.find("took their sign from the others"), std::string::npos);
    }
    EXPECT_GT(m_last.grazing_flipped, 0u);
    // Without a sensor: propagation over the whole k-NN graph from each component's top.
    options.no_sensor = true;
    expect_equal(file, options, 150, 200000);
    expect_equal(file, options, 2000, std::uint64_t(1) << 30);
    EXPECT_GT(m_last.components, 0u);
    EXPECT_NE(m_last.normals_detail.find("components seeded at their highest point"), std::string::npos);
}

TEST_F(ImportOutOfCore, PlyWithNormalsAndDecimationEqualsInCore) {
    const auto file = write("scan.ply", ply_bytes(synthetic_scan(true), nullptr));
    Options options;
    expect_equal(file, options, 300, 200000);
    EXPECT_GT(m_last.clean.zero_normal, 0u);
    options.keep_fraction = 0.7;
    options.keep_duplicates = true;
    options.outliers.radius_factor = 0;
    expect_equal(file, options, 300, 200000);
    EXPECT_GT(m_last.decimated, 0u);
    options.normals = NormalsMode::keep;
    options.outliers.enabled = false;
    expect_equal(file, options, 300, 200000);
}

TEST_F(ImportOutOfCore, XyzWithSensorOptionsEqualsInCore) {
    const auto file = write("scan.xyz", xyz_bytes(synthetic_scan(false)));
    Options options;
    options.grazing_cos = 0;
    options.sensor = k_scanner;
    expect_equal(file, options, 250, 150000);
    EXPECT_GT(m_last.malformed_lines, 0u);
    options.sensor.reset();
    options.sensor_direction = std::array<double, 3>{0.2, -0.1, 1.0};
    options.normals = NormalsMode::estimate;
    expect_equal(file, options, 250, 150000);
    const auto with_normals = write("normals.xyz", xyz_bytes(synthetic_scan(true)));
    expect_equal(with_normals, Options{}, 400, 150000);
    EXPECT_TRUE(m_last.normals_from_file);
}

TEST_F(ImportOutOfCore, PoolInputEqualsInCore) {
    // A pool written from the synthetic scan (normals estimated, the camera as its sensor, colours,
    // intensities), imported again: the file's normals kept, or estimated afresh.
    const auto ply = write("scan.ply", ply_bytes(synthetic_scan(false), &k_scanner));
    Report first;
    Options options;
    options.quiet = true;
    const prt::pre::PointCloud cloud = import_file(ply, options, first);
    prt::pool::PoolWriter writer;
    prt::pre::write_point_sections(cloud, writer);
    writer.write(path("scan.pool"));
    expect_equal(path("scan.pool"), Options{}, 300, std::uint64_t(16) << 20);
    EXPECT_TRUE(m_last.normals_from_file);
    EXPECT_EQ(m_last.pools.size(), 1u);
    options.normals = NormalsMode::estimate;
    options.keep_fraction = 0.8;
    expect_equal(path("scan.pool"), options, 300, std::uint64_t(16) << 20);
    EXPECT_TRUE(m_last.normals_estimated);
}

TEST_F(ImportOutOfCore, WhatIsNotOutOfCoreIsOneLineNamingTheOption) {
    const auto ply = write("scan.ply", ply_bytes(synthetic_scan(false, 200), nullptr));
    Options options;
    options.quiet = true;
    const ImportEstimate e = estimate_import(ply, options);
    EXPECT_EQ(e.points, 200u + 1200 + 12 + 40 + 2);
    EXPECT_GT(e.bytes, e.points * 100);
    EXPECT_EQ(e.unsupported, "");  // no sensor: propagation over the whole graph, out of core too
    options.sensor = k_scanner;
    EXPECT_EQ(estimate_import(ply, options).unsupported, "");
    const auto pcd = write("scan.pcd", "VERSION .7\n");
    const std::string msg = estimate_import(pcd, options).unsupported;
    EXPECT_EQ(msg.rfind(pcd.string() + ": PCD", 0), 0u) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos);
    MemoryParams mem;
    mem.spill_folder = m_dir;
    Report report;
    const auto obj = write("mesh.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const std::string err = error_of([&] { import_file_out_of_core(obj, options, mem, report); });
    EXPECT_EQ(err.rfind(obj.string() + ": a mesh", 0), 0u) << err;
    // The grazing normals' edges must fit the memory: else one line saying to raise it.
    options.sensor = k_scanner;
    options.grazing_cos = 0.9;
    mem.memory = 20000;
    mem.tile_points = 200;
    const std::string big = error_of([&] { import_file_out_of_core(ply, options, mem, report); });
    EXPECT_EQ(big.rfind(ply.string() + ": --grazing-cos 0.9", 0), 0u) << big;
    EXPECT_NE(big.find("raise --memory"), std::string::npos) << big;
}

class MergedOutOfCore : public ImportOutOfCore {
protected:
    void expect_merged_equal(const fs::path& poses, Options options, std::uint64_t tile, std::uint64_t memory,
                             const std::vector<fs::path>& only = {}) {
        SCOPED_TRACE("merged, tile " + std::to_string(tile));
        options.quiet = true;
        Report in_report, out_report;
        const prt::pre::PointCloud cloud = import_merged(poses, only, options, in_report);
        prt::pool::PoolWriter in_writer;
        prt::pre::write_point_sections(cloud, in_writer);
        MemoryParams mem;
        mem.memory = memory;
        mem.tile_points = tile;
        mem.spill_folder = m_dir;
        const SpilledCloud spilled = import_merged_out_of_core(poses, only, options, mem, out_report);
        prt::pool::PoolWriter out_writer;
        write_point_sections(spilled, mem, out_writer);
        const std::vector<std::byte> a = in_writer.serialize(), b = out_writer.serialize();
        const prt::pool::PoolFile pa = prt::pool::PoolFile::from_bytes(a, "in core");
        const prt::pool::PoolFile pb = prt::pool::PoolFile::from_bytes(b, "out of core");
        ASSERT_EQ(pa.sections().size(), pb.sections().size());
        for (std::size_t i = 0; i < pa.sections().size(); ++i) {
            const auto& ea = pa.sections()[i];
            const auto& eb = pb.sections()[i];
            SCOPED_TRACE("section " + std::string(ea.name, strnlen(ea.name, sizeof ea.name)));
            EXPECT_EQ(ea.type, eb.type);
            const auto sa = pa.bytes(ea);
            const auto sb = pb.bytes(eb);
            ASSERT_EQ(sa.size(), sb.size());
            EXPECT_TRUE(std::equal(sa.begin(), sa.end(), sb.begin()));
        }
        EXPECT_EQ(a, b);
        EXPECT_EQ(in_report.clean.summary(), out_report.clean.summary());
        EXPECT_EQ(in_report.outliers.removed, out_report.outliers.removed);
        EXPECT_EQ(in_report.records, out_report.records);
        EXPECT_EQ(in_report.ambiguous, out_report.ambiguous);
        EXPECT_EQ(in_report.grazing_flipped, out_report.grazing_flipped);
        EXPECT_EQ(in_report.estimate_failed, out_report.estimate_failed);
        EXPECT_EQ(in_report.sensors_detail, out_report.sensors_detail);
        ASSERT_EQ(in_report.scans.size(), out_report.scans.size());
        for (std::size_t s = 0; s < in_report.scans.size(); ++s)
            EXPECT_EQ(in_report.scans[s].clean.summary(), out_report.scans[s].clean.summary());
        m_last = in_report;
    }
};

TEST_F(MergedOutOfCore, PoseListOfPlyAndXyzScansEqualsInCore) {
    // Three scans in their own frames (one with normals, one with a camera, one XYZ), moved by a
    // JSON pose list; the third repeats part of the first in the merged frame: duplicates across scans.
    const Scan a = synthetic_scan(false, 1500), b = synthetic_scan(true, 1200);
    write("a.ply", ply_bytes(a, &k_scanner));
    write("b.ply", ply_bytes(b, nullptr));
    write("c.xyz", xyz_bytes(synthetic_scan(false, 900)));
    const auto poses = write("poses.json", R"({"scans": [
        {"file": "a.ply"},
        {"file": "b.ply", "matrix": [0, -1, 0, 10,  1, 0, 0, 20,  0, 0, 1, 3,  0, 0, 0, 1],
         "sensor": {"point": [450001, 5200001, 125]}},
        {"file": "c.xyz", "translation": [0.5, 0.25, 0], "quaternion": {"w": 1, "x": 0, "y": 0, "z": 0},
         "sensor": {"direction": [0.1, 0.2, 1]}}
      ]})");
    Options options;
    expect_merged_equal(poses, options, 300, std::uint64_t(16) << 20);
    EXPECT_NE(m_last.sensors_detail.find("3 (one per scan)"), std::string::npos) << m_last.sensors_detail;
    EXPECT_GT(m_last.clean.duplicates + m_last.outliers.removed, 0u);
    EXPECT_NE(m_last.normals_detail.find("kept from the files"), std::string::npos) << m_last.normals_detail;
    options.grazing_cos = 0;
    options.keep_duplicates = true;
    expect_merged_equal(poses, options, 1000, std::uint64_t(16) << 20);
    options.normals = NormalsMode::keep;
    expect_merged_equal(poses, options, 1000, std::uint64_t(16) << 20);
    options.normals = NormalsMode::estimate;
    options.sensor = k_scanner;
    expect_merged_equal(poses, options, 500, std::uint64_t(16) << 20);
    // Without sensors: the file's normals kept and fixed, the others propagated over the graph.
    options = Options{};
    options.no_sensor = true;
    expect_merged_equal(poses, options, 400, std::uint64_t(16) << 20);
    EXPECT_NE(m_last.normals_detail.find("from the file's normals, then"), std::string::npos)
        << m_last.normals_detail;
}

fs::path real_data(const std::string& rel) {
    return fs::path(PRT_SHARED_DATA_DIR) / "points" / rel;
}

TEST_F(MergedOutOfCore, RealBunnyScansEqualInCore) {
    // Three raw Stanford bunny scans merged by bun.conf (a sensor per scan, grazing normals).
    const auto conf = real_data("stanford_bunny/data/bun.conf");
    if (!fs::exists(conf)) GTEST_SKIP() << "real data absent: " << conf << " (../shared/data not mounted)";
    const fs::path dir = conf.parent_path();
    expect_merged_equal(conf, Options{}, 20000, std::uint64_t(64) << 20,
                        {dir / "bun000.ply", dir / "bun045.ply", dir / "bun090.ply"});
    EXPECT_GT(m_last.grazing_flipped, 0u);
    EXPECT_GT(m_last.written, 100000u);
}

TEST_F(ImportOutOfCore, RealScansEqualInCore) {
    // The CGAL kitten (XYZ with normals) and one raw Stanford bunny scan (ASCII PLY, its vertices;
    // the scanner far along +z of the scan's frame, bun.conf's convention).
    const auto kitten = real_data("cgal_kitten/kitten.xyz");
    const auto bunny = real_data("stanford_bunny/data/bun000.ply");
    if (!fs::exists(kitten) || !fs::exists(bunny))
        GTEST_SKIP() << "real data absent: " << kitten << " or " << bunny << " (../shared/data not mounted)";
    expect_equal(kitten, Options{}, 700, 300000);
    EXPECT_EQ(m_last.written, 5210u);
    Options options;
    options.mesh_mode = MeshMode::points;
    options.sensor_direction = std::array<double, 3>{0, 0, 1};
    options.grazing_cos = 0;
    expect_equal(bunny, options, 4000, 2000000);
    EXPECT_GT(m_last.written, 30000u);
}

class GrazingPropagation : public TempDirTest {};

TEST_F(GrazingPropagation, TakesTheStepsOfOrientByPropagation) {
    // A random graph (rows read in a shuffled order, as tiles give them) with normals from a small
    // set of opposite and oblique directions (ties of |n_i . n_j| everywhere, so the order of the
    // adjacency lists decides the signs), invalid normals, short rows and z ties for the seeds.
    std::mt19937 rng(5);
    const std::uint32_t n = 3000, k = 6;
    const Float3 set[] = {{0, 0, 1},       {0, 0, -1},      {1, 0, 0},
                          {-1, 0, 0},      {0.6f, 0, 0.8f}, {-0.6f, 0, -0.8f},
                          {0, 0.8f, 0.6f}, {0, 0, 0},       {std::nanf(""), 0, 1}};
    for (const int percent_fixed : {50, 5}) {
        std::vector<std::array<double, 3>> positions(n);
        std::vector<Float3> normals(n);
        std::vector<std::uint8_t> fixed(n), state(n);
        KnnGraph graph;
        graph.k = k;
        graph.neighbours.assign(std::size_t(n) * k, k_no_neighbour);
        for (std::uint32_t i = 0; i < n; ++i) {
            positions[i] = {0, 0, double(rng() % 20)};
            normals[i] = set[rng() % (rng() % 10 == 0 ? 9 : 7)];
            fixed[i] = int(rng() % 100) < percent_fixed;
            const std::uint32_t len = rng() % 20 == 0 ? k / 2 : k;
            for (std::uint32_t j = 0; j < len; ++j) {
                std::uint32_t m = rng() % n;
                while (m == i) m = rng() % n;
                graph.neighbours[std::size_t(i) * k + j] = m;
            }
            const float l =
                normals[i].x * normals[i].x + normals[i].y * normals[i].y + normals[i].z * normals[i].z;
            state[i] = !(std::isfinite(l) && l > 1e-12f) ? 0 : fixed[i] ? 1 : 2;
        }
        std::vector<Float3> want = normals;
        const OrientStats stats = orient_by_propagation(positions, want, graph, true, &fixed);
        std::vector<std::uint32_t> order(n);
        for (std::uint32_t i = 0; i < n; ++i) order[i] = i;
        std::shuffle(order.begin(), order.end(), rng);
        std::vector<GrazingEdge> edges;
        for (const std::uint32_t g : order)
            add_grazing_edges(g, graph.neighbours.data() + std::size_t(g) * k, k, state, edges);
        std::vector<Float3> got = normals;
        const std::uint64_t flipped = propagate_grazing(
            std::move(edges), state, got, [&](std::uint32_t i) { return positions[i][2]; },
            std::uint64_t(1) << 30, [] { throw prt::Error("too big"); }, true);
        EXPECT_GT(stats.flipped, 100u);
        EXPECT_EQ(flipped, stats.flipped);
        EXPECT_EQ(std::memcmp(got.data(), want.data(), n * sizeof(Float3)), 0);
        // The whole graph's propagation out of core (normals without a sensor), with and without sources.
        for (const bool sources : {true, false}) {
            std::vector<Float3> ref = normals, out = normals;
            const OrientStats a =
                orient_by_propagation(positions, ref, graph, true, sources ? &fixed : nullptr);
            const OrientStats b = orient_over_rows(
                graph.neighbours, k, out,
                sources ? std::span<const std::uint8_t>(fixed) : std::span<const std::uint8_t>{},
                [&](std::uint32_t i) { return positions[i][2]; }, m_dir, [] {}, true);
            EXPECT_EQ(a.components, b.components);
            EXPECT_EQ(a.ambiguous, b.ambiguous);
            EXPECT_EQ(a.flipped, b.flipped);
            EXPECT_EQ(a.skipped, b.skipped);
            EXPECT_EQ(std::memcmp(ref.data(), out.data(), n * sizeof(Float3)), 0);
        }
    }
}

class SpillFileAdvice : public TempDirTest {};

// The orientation's arrays are read and written at random; a kernel that keeps a file's page cache
// in large folios (Linux 6.x, ext4) maps a whole folio per fault, so 4096 scattered writes mapped
// nearly all of a 576 MB file. advise_random() (before the first touch) keeps single pages.
TEST_F(SpillFileAdvice, ScatteredWritesMapOnlyThePagesTheyTouch) {
    constexpr std::uint64_t bytes = std::uint64_t(64) << 20, page = 4096, touched = 256;
    const prt::pre::SpillFile file(m_dir, bytes, "the test's array");
    file.advise_random();
    std::memset(file.data(), 1, bytes);  // every page in the page cache
    file.drop();
    const std::uint64_t before = prt::pre::current_file_rss_bytes();
    std::mt19937_64 rng(5);
    for (std::uint64_t i = 0; i < touched; ++i) file.data()[(rng() % (bytes / page)) * page] = std::byte{2};
    const std::uint64_t after = prt::pre::current_file_rss_bytes();
    const std::uint64_t grown = after - std::min(before, after);
    EXPECT_LE(grown, touched * 16 * page) << "a write fault mapped more than a fault-around window";
    file.drop();
}

TEST(MedianStreamed, EqualsNthElement) {
    std::mt19937_64 rng(3);
    std::exponential_distribution<float> d(2.0f);
    for (const std::size_t n : {1u, 2u, 7u, 1000u, 65537u}) {
        std::vector<float> v(n);
        for (float& x : v) x = d(rng);
        if (n > 10) v[3] = std::numeric_limits<float>::infinity(), v[5] = 0.f, v[6] = v[7];
        std::vector<float> w = v;
        const std::size_t mid = (n - 1) / 2;
        std::nth_element(w.begin(), w.begin() + std::ptrdiff_t(mid), w.end());
        EXPECT_EQ(median_streamed(n, [&](std::uint64_t i) { return v[i]; }), w[mid]) << n;
    }
}

class ImportOutOfCoreTool : public TempDirTest {
protected:
    void SetUp() override {
        TempDirTest::SetUp();
        m_tool = fs::path(PRT_BIN_DIR) / "prt-import";
        if (!fs::exists(m_tool)) GTEST_SKIP() << "prt-import is not built in " << PRT_BIN_DIR;
    }
    int run(const std::string& args) {
        const std::string cmd = m_tool.string() + " " + args + " 2>" + path("err.txt").string();
        const int status = std::system(cmd.c_str());
        std::ifstream in(path("err.txt"));
        std::stringstream ss;
        ss << in.rdbuf();
        m_stderr = ss.str();
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    fs::path m_tool;
    std::string m_stderr;
};

TEST_F(ImportOutOfCoreTool, TilePointsGivesTheInCorePool) {
    const auto file = write("scan.ply", ply_bytes(synthetic_scan(false), &k_scanner));
    ASSERT_EQ(run(file.string() + " -o " + path("in.pool").string() + " --quiet"), 0) << m_stderr;
    ASSERT_EQ(run(file.string() + " -o " + path("out.pool").string() + " --tile-points 300 --memory 8M"), 0)
        << m_stderr;
    EXPECT_NE(m_stderr.find("out of core"), std::string::npos) << m_stderr;
    const auto a = prt::pool::PoolFile::open(path("in.pool"));
    const auto b = prt::pool::PoolFile::open(path("out.pool"));
    std::size_t compared = 0;
    for (const auto& e : a.sections()) {
        const auto t = static_cast<prt::pool::SectionType>(e.type);
        if (t == prt::pool::SectionType::provenance) continue;
        ASSERT_NE(b.find(t), nullptr) << e.name;
        const auto sa = a.bytes(e), sb = b.bytes(*b.find(t));
        ASSERT_EQ(sa.size(), sb.size()) << e.name;
        EXPECT_TRUE(std::equal(sa.begin(), sa.end(), sb.begin())) << e.name;
        ++compared;
    }
    EXPECT_EQ(compared, 6u);  // model_info, positions, normals, colors, intensities, sensors
    // A pose list and a pool input go out of core too, with the in-core pool.
    write("b.xyz", xyz_bytes(synthetic_scan(false, 600)));
    const auto poses = write("poses.json", R"({"scans": [{"file": "scan.ply"},
        {"file": "b.xyz", "translation": [3, 0, 0], "quaternion": {"w": 1, "x": 0, "y": 0, "z": 0},
         "sensor": {"direction": [0, 0, 1]}}]})");
    for (const std::string& input : {"--poses " + poses.string(), path("in.pool").string()}) {
        SCOPED_TRACE(input);
        ASSERT_EQ(run(input + " -o " + path("m_in.pool").string() + " --quiet"), 0) << m_stderr;
        ASSERT_EQ(run(input + " -o " + path("m_out.pool").string() + " --tile-points 400 --memory 8M"), 0)
            << m_stderr;
        EXPECT_NE(m_stderr.find("out of core"), std::string::npos) << m_stderr;
        const auto c = prt::pool::PoolFile::open(path("m_in.pool"));
        const auto d = prt::pool::PoolFile::open(path("m_out.pool"));
        ASSERT_EQ(c.sections().size(), d.sections().size());
        for (const auto& e : c.sections()) {
            const auto t = static_cast<prt::pool::SectionType>(e.type);
            ASSERT_NE(d.find(t), nullptr) << e.name;
            if (t == prt::pool::SectionType::provenance) continue;  // times differ
            const auto sa = c.bytes(e), sb = d.bytes(*d.find(t));
            ASSERT_EQ(sa.size(), sb.size()) << e.name;
            EXPECT_TRUE(std::equal(sa.begin(), sa.end(), sb.begin())) << e.name;
        }
    }
    // Not out of core: one line, exit 1, nothing written.
    const auto obj = write("mesh.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    EXPECT_EQ(run(obj.string() + " -o " + path("x.pool").string() + " --tile-points 300"), 1);
    EXPECT_NE(m_stderr.find("raise --memory"), std::string::npos) << m_stderr;
    EXPECT_EQ(std::count(m_stderr.begin(), m_stderr.end(), '\n'), 1) << m_stderr;
    EXPECT_FALSE(fs::exists(path("x.pool")));
}

}  // namespace
