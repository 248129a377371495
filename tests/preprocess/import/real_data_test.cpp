// The real scans and meshes of ../shared/data (skipped where the folder is absent): imported with
// the counts their sources state (data/README.md) or that an independent parse here finds.
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "import_test_util.h"

namespace {

using namespace prt_import_test;
using prt::pre::import::Options;
using prt::pre::import::Report;

fs::path data(const std::string& rel) {
    return fs::path(PRT_SHARED_DATA_DIR) / "points" / rel;
}

#define PRT_NEED(file) \
    if (!fs::exists(file)) GTEST_SKIP() << "real data absent: " << (file) << " (../shared/data not mounted)"

TEST(RealData, KittenXyz) {
    const auto file = data("cgal_kitten/kitten.xyz");
    PRT_NEED(file);
    Report report;
    const auto cloud = import(file, report);
    EXPECT_EQ(report.records, 5210u);
    EXPECT_EQ(cloud.size(), 5210u);
    EXPECT_TRUE(report.normals_from_file);
    EXPECT_EQ(report.malformed_lines, 0u);
}

TEST(RealData, BunnyZipperMesh) {
    const auto file = data("stanford_bunny/reconstruction/bun_zipper.ply");
    PRT_NEED(file);
    if (!prt::pre::import::have_openmesh()) GTEST_SKIP() << "this build has no OpenMesh";
    // Independent count of the vertices some face uses (the file is ASCII: header, vertices, faces).
    std::ifstream in(file);
    std::string line;
    std::size_t vertices = 0, faces = 0;
    while (std::getline(in, line) && line.rfind("end_header", 0) != 0) {
        std::istringstream words(line);
        std::string kw, name;
        std::size_t count = 0;
        if (words >> kw >> name >> count && kw == "element") (name == "vertex" ? vertices : faces) = count;
    }
    for (std::size_t i = 0; i < vertices; ++i) std::getline(in, line);
    std::set<std::size_t> used;
    for (std::size_t f = 0; f < faces && std::getline(in, line); ++f) {
        std::istringstream words(line);
        std::size_t n = 0, v = 0;
        words >> n;
        for (std::size_t k = 0; k < n && words >> v; ++k) used.insert(v);
    }
    ASSERT_EQ(vertices, 35947u);
    Report report;
    const auto cloud = import(file, report);
    EXPECT_EQ(report.records, 35947u);
    EXPECT_EQ(report.faces, faces);
    EXPECT_EQ(report.unreferenced_vertices, vertices - used.size());
    EXPECT_EQ(cloud.size(), used.size() - report.cancelled_normals);
    EXPECT_TRUE(report.normals_area_weighted);

    // As a point set: every vertex, PCA normals.
    if (!prt::pre::import::have_pcl()) return;
    Options points;
    points.mesh_mode = prt::pre::import::MeshMode::points;
    Report report2;
    const auto cloud2 = import(file, report2, points);
    EXPECT_EQ(report2.records, 35947u);
    EXPECT_EQ(cloud2.size() + report2.clean.duplicates + report2.outliers.removed + report2.estimate_failed,
              35947u);
    EXPECT_LT(report2.outliers.removed, 35947u / 200);  // under 0.5 %
    EXPECT_TRUE(report2.normals_estimated);
    EXPECT_TRUE(has_note(report2, "skipped vertex properties: confidence"));
    EXPECT_TRUE(cloud2.has_intensities());  // the zippered mesh's per-vertex intensity
}

/// A mesh through OpenMesh with its stated vertex and face counts: every vertex becomes a point
/// but those with a zero normal (at most `max_zero_normal` of them), which are dropped and counted.
void expect_mesh(const std::string& rel, std::size_t vertices, std::size_t faces,
                 std::size_t max_zero_normal) {
    const auto file = data(rel);
    PRT_NEED(file);
    if (!prt::pre::import::have_openmesh()) GTEST_SKIP() << "this build has no OpenMesh";
    Report report;
    const auto cloud = import(file, report);
    EXPECT_EQ(report.records, vertices);
    EXPECT_EQ(report.faces, faces);
    EXPECT_EQ(cloud.size() + report.clean.zero_normal, vertices);
    EXPECT_LE(report.clean.zero_normal, max_zero_normal);
}

TEST(RealData, DragonObj) {
    // Vertices whose faces cancel take the file's vn normal when it has one.
    expect_mesh("stanford_dragon/dragon_small.obj", 22998, 47794, 99);
}

TEST(RealData, ArmadilloOff) {
    expect_mesh("stanford_armadillo/armadillo.off", 26002, 52000, 0);
}

TEST(RealData, OrganizedPcdWithNans) {
    const auto file = data("pcl/table_scene_mug_stereo_textured.pcd");
    PRT_NEED(file);
    if (!prt::pre::import::have_pcl()) GTEST_SKIP() << "this build has no PCL";
    Options keep;
    keep.normals = prt::pre::import::NormalsMode::keep;  // estimation is timed in the tool test
    Report report;
    const auto cloud = import(file, report, keep);
    EXPECT_EQ(report.records, 307200u);
    EXPECT_EQ(report.nan_entries, 307200u - 209280u);
    EXPECT_EQ(cloud.size() + report.clean.duplicates + report.outliers.removed, 209280u);
    EXPECT_LT(report.outliers.removed, 209280u / 200);  // under 0.5 %
    EXPECT_TRUE(cloud.has_colors());
}

// One stereo view with its VIEWPOINT: every surface it saw faces the camera. Propagation alone
// (seeded +z, which in a camera frame points away from the camera) gets the sign wrong.
TEST(RealData, MugSceneNormalsFaceTheCamera) {
    const auto file = data("pcl/table_scene_mug_stereo_textured.pcd");
    PRT_NEED(file);
    if (!prt::pre::import::have_pcl()) GTEST_SKIP() << "this build has no PCL";
    auto facing = [&](const Options& o, Report& report) {
        const auto cloud = import(file, report, o);
        std::size_t strong = 0, face = 0;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            const auto& p = cloud.positions[i];
            const double l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            const double c =
                -(cloud.normals[i].x * p[0] + cloud.normals[i].y * p[1] + cloud.normals[i].z * p[2]) / l;
            if (std::fabs(c) <= 0.3) continue;
            ++strong;
            face += c > 0;
        }
        return double(face) / double(strong);
    };
    Report report;
    EXPECT_EQ(facing(Options{}, report), 1.0);
    EXPECT_TRUE(report.oriented_to_sensor);
    EXPECT_EQ(report.sensors_detail.rfind("1 point (0, 0, 0)", 0), 0u) << report.sensors_detail;
    EXPECT_LT(report.outliers.removed, 209280u / 200);  // under 0.5 %
    Options none;
    none.no_sensor = true;
    Report r2;
    EXPECT_LT(facing(none, r2), 0.01);
}

TEST(RealData, RawBunnyScansWithRangeGrids) {
    const char* scans[] = {"bun000", "bun045", "bun090",   "bun180", "bun270",
                           "bun315", "chin",   "ear_back", "top2",   "top3"};
    std::uint64_t total = 0;
    for (const char* s : scans) {
        const auto file = data(std::string("stanford_bunny/data/") + s + ".ply");
        PRT_NEED(file);
        Options keep;
        keep.normals = prt::pre::import::NormalsMode::keep;
        keep.keep_duplicates = true;
        Report report;
        keep.outliers.enabled = false;
        total += import(file, report, keep).size();
        EXPECT_TRUE(has_note(report, "skipped elements: range_grid")) << s;
    }
    EXPECT_EQ(total, 362272u);
}

}  // namespace
