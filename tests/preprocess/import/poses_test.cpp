// Pose lists (--poses): Stanford .conf and our JSON, parsed and checked (every bad entry one line
// naming the pose file and the line or entry); merged imports of synthetic scans whose true world
// coordinates are known; and the ten real bunny scans against the zippered mesh: the pose
// convention (distance to bun_zipper.ply) and the orientation of estimated normals.
#include "poses.h"

#include <cmath>
#include <cstdio>
#include <random>

#include "import_test_util.h"
#include "scan_reference.h"

namespace {

using namespace prt_import_test;
using prt::pre::import::Options;
using prt::pre::import::PoseEntry;
using prt::pre::import::Report;
using Vec3 = std::array<double, 3>;

/// Rotates v by the unit quaternion (w, x, y, z) as q v q* (Hamilton products written out here).
Vec3 quat_rotate(double w, double x, double y, double z, const Vec3& v) {
    const double n = std::sqrt(w * w + x * x + y * y + z * z);
    w /= n, x /= n, y /= n, z /= n;
    // t = q v (v as a pure quaternion)
    const double tw = -x * v[0] - y * v[1] - z * v[2];
    const double tx = w * v[0] + y * v[2] - z * v[1];
    const double ty = w * v[1] + z * v[0] - x * v[2];
    const double tz = w * v[2] + x * v[1] - y * v[0];
    // t q*  with q* = (w, -x, -y, -z)
    return {-tw * x + tx * w - ty * z + tz * y, -tw * y + ty * w - tz * x + tx * z,
            -tw * z + tz * w - tx * y + ty * x};
}

using Poses = TempDirTest;

/// Reading the pose list `file` (whose text is `text`) fails with one line, "<file>: ...", containing
/// `expect`.
void expect_pose_error(const fs::path& file, const std::string& text, const char* expect) {
    const std::string msg = error_of([&] { prt::pre::import::read_poses(file); });
    EXPECT_EQ(msg.rfind(file.string() + ": ", 0), 0u) << msg;
    EXPECT_NE(msg.find(expect), std::string::npos) << text << " -> " << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
}

TEST_F(Poses, StanfordConf) {
    write("a.xyz", "0 0 0\n");
    fs::create_directories(path("sub"));
    write("sub/b.xyz", "0 0 0\n");
    const auto conf = write("scans.conf",
                            "camera -0.0172 -0.0936 -0.734  -0.0461723 0.970603 -0.235889 0.0124573\n"
                            "# a comment\n\n"
                            "bmesh a.xyz 0 0 0 0 0 0 1\n"
                            "bmesh sub/b.xyz 1 -2 3.5 0.00548449 -0.294635 -0.0038555 0.955586\n");
    const std::vector<PoseEntry> e = prt::pre::import::read_poses(conf);
    ASSERT_EQ(e.size(), 2u);
    EXPECT_EQ(e[0].file, path("a.xyz"));
    EXPECT_EQ(e[1].file, path("sub/b.xyz"));
    EXPECT_TRUE(e[0].pose.is_identity());
    EXPECT_NE(e[1].where.find("scans.conf: line 5"), std::string::npos) << e[1].where;
    // p -> R(q)^-1 p + t, q = (qi qj qk qr): the conjugate's rotation.
    const Vec3 v{0.3, -1.2, 2.0};
    const Vec3 want = quat_rotate(0.955586, -0.00548449, 0.294635, 0.0038555, v);
    const Vec3 got = e[1].pose.apply(v);
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(got[a], want[a] + e[1].pose.t[a], 1e-12);
    EXPECT_EQ(e[1].pose.t[2], 3.5);
    ASSERT_TRUE(e[1].sensor);
    EXPECT_EQ(e[1].sensor->kind, prt::pool::k_sensor_direction);
    EXPECT_EQ(e[1].sensor->position[2], 1.0);
    // The sensor direction in the merged frame: +z of the scan's frame turned by R(q)^-1.
    const prt::pool::Sensor s = e[1].pose.apply(*e[1].sensor);
    const Vec3 z = quat_rotate(0.955586, -0.00548449, 0.294635, 0.0038555, {0, 0, 1});
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(s.position[a], z[a], 1e-6);
}

TEST_F(Poses, StanfordConfErrorsNameTheLine) {
    write("a.xyz", "0 0 0\n");
    struct Case {
        const char* text;
        const char* expect;
    };
    const Case cases[] = {
        {"bmesh a.xyz 0 0 0 0 0 1\n",
         "line 1: bmesh needs FILE tx ty tz qi qj qk qr (8 fields after bmesh), got 7"},
        {"camera 1 2 3\nbmesh a.xyz 0 0 0 0 0 0 1 9\n", "line 2: bmesh needs FILE tx ty tz qi qj qk qr"},
        {"bmesh a.xyz 0 nan 0 0 0 0 1\n", "line 1: ty 'nan' is not finite"},
        {"bmesh a.xyz 0 0 inf 0 0 0 1\n", "line 1: tz 'inf' is not finite"},
        {"bmesh a.xyz 0 0 0 0 0 0 x\n", "line 1: qr 'x' is not a number"},
        {"bmesh a.xyz 0 0 0 0 0 0 1.01\n", "line 1: the quaternion has norm 1.01, not 1 (within 0.001)"},
        {"bmesh a.xyz 0 0 0 0 0 0 0\n", "line 1: the quaternion has norm 0, not 1"},
        {"\n\nbmesh missing.xyz 0 0 0 0 0 0 1\n", "line 3: scan file"},
        {"mesh a.xyz 0 0 0 0 0 0 1\n", "line 1: unknown keyword 'mesh'"},
        {"camera 0 0 0 0 0 0 1\n", "no bmesh line"},
    };
    for (const Case& c : cases) expect_pose_error(write("bad.conf", c.text), c.text, c.expect);
}

TEST_F(Poses, JsonPoseList) {
    write("a.ply", "ply\n");
    write("b.ply", "ply\n");
    write("c.ply", "ply\n");
    const double h = std::sqrt(0.5);
    char text[2048];
    std::snprintf(text, sizeof text,
                  R"({"comment": "three scans",
  "scans": [
    {"file": "a.ply", "matrix": [0, -1, 0, 10,  1, 0, 0, 20,  0, 0, 1, 30,  0, 0, 0, 1],
     "sensor": {"point": [1, 2, 3]}},
    {"file": "b.ply", "translation": [1, 2, 3], "quaternion": {"w": %.17g, "x": 0, "y": 0, "z": %.17g},
     "sensor": {"direction": [0, 0, 2]}},
    {"file": "c.ply", "sensor": null}
  ]})",
                  h, h);
    const auto json = write("poses.json", text);
    const auto e = prt::pre::import::read_poses(json);
    ASSERT_EQ(e.size(), 3u);
    // a: 90 degrees about z, then (10, 20, 30).
    const Vec3 pa = e[0].pose.apply(Vec3{1, 0, 0});
    EXPECT_NEAR(pa[0], 10, 1e-12);
    EXPECT_NEAR(pa[1], 21, 1e-12);
    EXPECT_NEAR(pa[2], 30, 1e-12);
    ASSERT_TRUE(e[0].sensor_given && e[0].sensor);
    const auto sa = e[0].pose.apply(*e[0].sensor);
    EXPECT_NEAR(sa.position[0], 8, 1e-12);  // (-2, 1, 3) + (10, 20, 30)
    EXPECT_NEAR(sa.position[1], 21, 1e-12);
    EXPECT_NEAR(sa.position[2], 33, 1e-12);
    // b: R(q) p + t with the same rotation as a quaternion (scalar w, Hamilton).
    const Vec3 pb = e[1].pose.apply(Vec3{1, 0, 0});
    EXPECT_NEAR(pb[0], 1, 1e-12);
    EXPECT_NEAR(pb[1], 3, 1e-12);
    EXPECT_NEAR(pb[2], 3, 1e-12);
    EXPECT_EQ(e[1].sensor->kind, prt::pool::k_sensor_direction);
    EXPECT_NEAR(e[1].sensor->position[2], 1.0, 1e-15);  // normalised
    // c: identity, and "sensor": null means no sensor even if the file has one.
    EXPECT_TRUE(e[2].pose.is_identity());
    EXPECT_TRUE(e[2].sensor_given);
    EXPECT_FALSE(e[2].sensor);
}

TEST_F(Poses, JsonErrorsNameTheEntry) {
    write("a.ply", "ply\n");
    struct Case {
        std::string text;
        const char* expect;
    };
    auto one = [](const std::string& fields) {
        return R"({"scans": [{"file": "a.ply"}, {"file": "a.ply", )" + fields + "}]}";
    };
    const Case cases[] = {
        {one(R"("matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0])"),
         "scans[1]: matrix has 15 numbers, expected 16 (4x4, row-major)"},
        {one(R"("matrix": [2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1])"),
         "scans[1]: matrix is not rigid"},
        {one(R"("matrix": [1, 0.1, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1])"),
         "scans[1]: matrix is not rigid"},
        {one(R"("matrix": [1, 0, 0, 0, 0, 1.000002, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1])"),
         "scans[1]: matrix is not rigid"},
        {one(R"("matrix": [-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1])"),
         "scans[1]: matrix has determinant -1"},
        {one(R"("matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1])"),
         "scans[1]: matrix's last row is 0 0 1 1"},
        {one(R"("matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, "nan", 0, 0, 0, 1])"),
         "scans[1]: matrix[11] is not a number"},
        {one(R"("matrix": [1, 0, 0, 1e999, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1])"), "invalid JSON"},
        {one(R"("quaternion": {"w": 1, "x": 1, "y": 0, "z": 0})"),
         "scans[1]: the quaternion has norm 1.41421, not 1"},
        {one(R"("quaternion": {"w": 0, "x": 0, "y": 0, "z": 0})"), "scans[1]: the quaternion has norm 0"},
        {one(R"("quaternion": [1, 0, 0, 0])"), "scans[1]: quaternion must be {\"w\""},
        {one(R"("translation": [1, 2])"), "scans[1]: translation must be an array of 3 numbers, got 2"},
        {one(R"("translation": [1, 2, 3], "matrix": [])"),
         "give either \"matrix\" or \"translation\"/\"quaternion\""},
        {one(R"("sensor": {"direction": [0, 0, 0]})"), "scans[1]: sensor.direction is zero"},
        {one(R"("sensor": {"point": [0, 0, 0], "direction": [0, 0, 1]})"), "scans[1]: sensor must be"},
        {one(R"("scale": 2)"), "scans[1]: unknown key 'scale'"},
        {R"({"scans": [{"file": "missing.ply"}]})", "scans[0]: scan file"},
        {R"({"scans": []})", "\"scans\" is empty"},
        {R"({"scans": [{"file": "a.ply"}],})", "line 1: invalid JSON"},
        {"{\"scans\": [\n{\"file\": \"a.ply\"},\n{\"file\": }]}", "line 3: invalid JSON"},
    };
    for (const Case& c : cases) expect_pose_error(write("bad.json", c.text), c.text, c.expect);
}

// Two scans of one wavy sheet, each stored in its own frame; the pose list brings them back.
// Scan A's sensor is above the sheet, scan B's below: each point's normal faces its own sensor.
TEST_F(Poses, MergedImportRestoresTheWorldAndOrientsPerScan) {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(0, 1);
    auto sheet = [&](double x0, int n) {
        std::vector<Vec3> pts;
        for (int i = 0; i < n; ++i) {
            const double x = x0 + u(rng), y = u(rng);
            pts.push_back({x, y, 0.05 * std::sin(3 * x) * std::cos(2 * y)});
        }
        return pts;
    };
    const auto world_a = sheet(0.0, 4000), world_b = sheet(0.8, 4000);  // they overlap in x 0.8..1
    // Scan frames: A turned 90 degrees about z and moved; B turned 180 degrees about x and moved.
    auto to_a = [](const Vec3& p) {
        return Vec3{p[1] - 20, -(p[0] - 10), p[2] - 30};
    };  // inverse of the pose
    auto to_b = [](const Vec3& p) { return Vec3{p[0] + 5, -p[1], -p[2]}; };
    std::vector<Vec3> file_a, file_b;
    for (const auto& p : world_a) file_a.push_back(to_a(p));
    for (const auto& p : world_b) file_b.push_back(to_b(p));
    write("a.xyz", xyz_text(file_a));
    write("b.xyz", xyz_text(file_b));
    // Sensor A at world (0.5, 0.5, 4): in A's frame (0.5 - 20, -(0.5 - 10), 4 - 30).
    // Sensor B at world (1.3, 0.5, -4) (below): in B's frame (6.3, -0.5, 4).
    const auto json = write("poses.json", R"({"scans": [
        {"file": "a.xyz", "matrix": [0, -1, 0, 10,  1, 0, 0, 20,  0, 0, 1, 30,  0, 0, 0, 1],
         "sensor": {"point": [-19.5, 9.5, -26]}},
        {"file": "b.xyz", "translation": [-5, 0, 0], "quaternion": {"w": 0, "x": 1, "y": 0, "z": 0},
         "sensor": {"point": [6.3, -0.5, 4]}}]})");
    Options options;
    options.quiet = true;
    Report report;
    const auto cloud = prt::pre::import::import_merged(json, {}, options, report);
    ASSERT_EQ(report.scans.size(), 2u);
    EXPECT_EQ(report.records, 8000u);
    ASSERT_EQ(cloud.size() + report.outliers.removed + report.clean.duplicates + report.estimate_failed,
              8000u);
    EXPECT_LT(report.outliers.removed, 40u);
    ASSERT_EQ(cloud.sensors.size(), 2u);
    EXPECT_NEAR(cloud.sensors[0].position[0], 0.5, 1e-12);
    EXPECT_NEAR(cloud.sensors[0].position[2], 4.0, 1e-12);
    EXPECT_NEAR(cloud.sensors[1].position[0], 1.3, 1e-12);
    EXPECT_NEAR(cloud.sensors[1].position[2], -4.0, 1e-12);
    ASSERT_EQ(cloud.scan_ids.size(), cloud.size());
    // Every merged point is a world point of its scan (the file holds 17 digits).
    const prt_scan_ref::GridNearest near_a(world_a), near_b(world_b);
    std::size_t far = 0, up = 0, down = 0, in_b = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const bool b = cloud.scan_ids[i] == 1;
        in_b += b;
        far += (b ? near_b : near_a).nearest(cloud.positions[i]).second > 1e-9;
        if (!b && cloud.normals[i].z > 0.5f) ++up;
        if (b && cloud.normals[i].z < -0.5f) ++down;
    }
    EXPECT_EQ(far, 0u);
    EXPECT_EQ(up, cloud.size() - in_b);
    EXPECT_EQ(down, in_b);
    EXPECT_TRUE(report.oriented_to_sensor);

    // Only one of the scans, by name.
    Report one;
    const auto only_b = prt::pre::import::import_merged(json, {path("b.xyz")}, options, one);
    EXPECT_EQ(one.scans.size(), 1u);
    EXPECT_EQ(only_b.sensors.size(), 1u);
    EXPECT_TRUE(only_b.scan_ids.empty());  // one sensor: no scan_ids
    const std::string msg = error_of([&] {
        Report r;
        prt::pre::import::import_merged(json, {path("c.xyz")}, options, r);
    });
    EXPECT_NE(msg.find("c.xyz: not listed in the pose file"), std::string::npos) << msg;
}

// ---- the real bunny scans ------------------------------------------------------------------------

fs::path bunny(const std::string& rel) {
    return fs::path(PRT_SHARED_DATA_DIR) / "points/stanford_bunny" / rel;
}

TEST(RealPoses, BunnyConfConventionMatchesTheMesh) {
    const auto conf = bunny("data/bun.conf");
    const auto mesh = bunny("reconstruction/bun_zipper.ply");
    if (!fs::exists(conf) || !fs::exists(mesh)) GTEST_SKIP() << "real data absent: " << conf;
    const prt_scan_ref::RefMesh ref = prt_scan_ref::read_ascii_ply_mesh(mesh.string());
    const prt_scan_ref::GridNearest nearest(ref.vertices);
    std::vector<std::vector<std::uint32_t>> around(ref.vertices.size());
    for (std::uint32_t t = 0; t < ref.triangles.size(); ++t)
        for (const std::uint32_t v : ref.triangles[t]) around[v].push_back(t);
    // Distance to the mesh: the triangles around the nearest vertex (and the vertex itself).
    // (Beyond 5 mm the search stops: the wrong readings of the pose are centimetres off.)
    auto to_mesh = [&](const Vec3& p) {
        const auto [v, dv] = nearest.nearest(p, 0.005);
        if (v == prt_scan_ref::GridNearest::k_none) return dv;
        double best = dv;
        for (const std::uint32_t t : around[v]) {
            const auto& tri = ref.triangles[t];
            best = std::min(best, prt_scan_ref::point_triangle(p, ref.vertices[tri[0]], ref.vertices[tri[1]],
                                                               ref.vertices[tri[2]]));
        }
        return best;
    };

    // The raw scans, posed here by the stated rule and by the three other readings of the line.
    std::ifstream in(conf);
    std::string kw, file;
    double t[3], q[4];  // q = qi qj qk qr
    double sum[4] = {0, 0, 0, 0};
    std::size_t count = 0;
    std::vector<Vec3> expected;
    while (in >> kw) {
        if (kw == "camera") {
            std::getline(in, kw);
            continue;
        }
        in >> file >> t[0] >> t[1] >> t[2] >> q[0] >> q[1] >> q[2] >> q[3];
        Options keep;
        keep.normals = prt::pre::import::NormalsMode::keep;
        keep.outliers.enabled = false;
        Report r;
        const auto scan = import(bunny("data/" + file), r, keep);
        for (std::size_t i = 0; i < scan.size(); ++i) {
            const Vec3& p = scan.positions[i];
            const Vec3 inv = quat_rotate(q[3], -q[0], -q[1], -q[2], p);  // R(q)^-1 p, scalar last
            const Vec3 fwd = quat_rotate(q[3], q[0], q[1], q[2], p);     // R(q) p
            const Vec3 first = quat_rotate(q[0], q[1], q[2], q[3], p);   // scalar first
            const Vec3 first_inv = quat_rotate(q[0], -q[1], -q[2], -q[3], p);
            expected.push_back({inv[0] + t[0], inv[1] + t[1], inv[2] + t[2]});
            if (i % 20 != 0) continue;
            const Vec3* readings[4] = {&inv, &fwd, &first, &first_inv};
            for (int k = 0; k < 4; ++k)
                sum[k] +=
                    to_mesh({(*readings[k])[0] + t[0], (*readings[k])[1] + t[1], (*readings[k])[2] + t[2]});
            ++count;
        }
    }
    const double mean = sum[0] / double(count);
    std::printf(
        "mean distance of posed points to bun_zipper.ply: R(q)^-1 p + t %.4f mm; R(q) p + t %.3f mm; "
        "scalar first %.3f / %.3f mm (%zu points)\n",
        1e3 * mean, 1e3 * sum[1] / double(count), 1e3 * sum[2] / double(count), 1e3 * sum[3] / double(count),
        count);
    EXPECT_LT(mean, 0.00015);  // the data README: 0.10 mm; the bunny is about 150 mm tall
    for (int k = 1; k < 4; ++k) EXPECT_GT(sum[k] / double(count), 10 * mean) << k;

    // prt-import's merged import does exactly this (outliers kept, duplicates kept, no normals).
    Options keep;
    keep.normals = prt::pre::import::NormalsMode::keep;
    keep.outliers.enabled = false;
    keep.keep_duplicates = true;
    Report report;
    const auto merged = prt::pre::import::import_merged(conf, {}, keep, report);
    ASSERT_EQ(merged.size(), expected.size());
    ASSERT_EQ(merged.size(), 362272u);
    double worst = 0;
    for (std::size_t i = 0; i < merged.size(); ++i)
        for (int a = 0; a < 3; ++a)
            worst = std::max(worst, std::fabs(merged.positions[i][a] - expected[i][a]));
    EXPECT_LT(worst, 1e-12);
    EXPECT_EQ(merged.sensors.size(), 10u);
}

/// Share of normals agreeing in sign with bun_zipper.ply's area-weighted normal at the nearest vertex.
double agreement(const prt::pre::PointCloud& c, const prt_scan_ref::RefMesh& ref,
                 const prt_scan_ref::GridNearest& near) {
    std::size_t agree = 0, counted = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        const auto& n = ref.normals[near.nearest(c.positions[i]).first];
        if (n[0] == 0 && n[1] == 0 && n[2] == 0) continue;
        ++counted;
        agree += n[0] * c.normals[i].x + n[1] * c.normals[i].y + n[2] * c.normals[i].z > 0;
    }
    return double(agree) / double(counted);
}

TEST(RealPoses, BunnyNormalsFaceTheirScanners) {
    const auto conf = bunny("data/bun.conf");
    const auto mesh = bunny("reconstruction/bun_zipper.ply");
    if (!fs::exists(conf) || !fs::exists(mesh)) GTEST_SKIP() << "real data absent: " << conf;
    const prt_scan_ref::RefMesh ref = prt_scan_ref::read_ascii_ply_mesh(mesh.string());
    const prt_scan_ref::GridNearest near(ref.vertices);
    // Three of the scans (the test stays fast): bun000, bun180 (the back) and top2.
    const std::vector<fs::path> some = {bunny("data/bun000.ply"), bunny("data/bun180.ply"),
                                        bunny("data/top2.ply")};
    Options options;
    options.quiet = true;
    Report with;
    const auto sensed = prt::pre::import::import_merged(conf, some, options, with);
    EXPECT_EQ(sensed.sensors.size(), 3u);
    EXPECT_TRUE(with.oriented_to_sensor);
    const double a_default = agreement(sensed, ref, near);
    options.grazing_cos = 0;  // every sign from its own sensor
    Report alone;
    const double a_sensor = agreement(prt::pre::import::import_merged(conf, some, options, alone), ref, near);
    options.no_sensor = true;
    Report without;
    const auto propagated = prt::pre::import::import_merged(conf, some, options, without);
    EXPECT_TRUE(propagated.sensors.empty());
    const double a_prop = agreement(propagated, ref, near);
    std::printf(
        "bunny (bun000, bun180, top2): normals agreeing with the mesh: %.4f by default (sensor, grazing "
        "from neighbours: %llu flipped), %.4f every sign from the sensor (%llu grazing), %.4f by "
        "propagation\n",
        a_default, static_cast<unsigned long long>(with.grazing_flipped), a_sensor,
        static_cast<unsigned long long>(alone.ambiguous), a_prop);
    EXPECT_GT(a_default, 0.999);
    EXPECT_GT(a_sensor, 0.995);
    EXPECT_GE(a_default, a_sensor);
}

}  // namespace
