// Normal estimation (PCA over our k-NN, neighbours.h) and orientation (Hoppe-style propagation, or
// toward a sensor) on synthetic shapes generated here, against their analytic normals.
#include <cmath>
#include <cstdio>
#include <random>

#include "import_test_util.h"
#include "orient.h"

namespace {

using namespace prt_import_test;
using prt::pre::import::Options;
using prt::pre::import::Report;

constexpr double k_pi = 3.14159265358979323846;

/// n points spread evenly over a sphere (Fibonacci lattice), as "x y z" lines.
std::vector<std::array<double, 3>> fibonacci_sphere(int n, std::array<double, 3> centre, double radius) {
    std::vector<std::array<double, 3>> pts;
    const double golden = k_pi * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / n;
        const double r = std::sqrt(1.0 - z * z);
        const double phi = golden * i;
        pts.push_back({centre[0] + radius * r * std::cos(phi), centre[1] + radius * r * std::sin(phi),
                       centre[2] + radius * z});
    }
    return pts;
}

struct SphereCheck {
    double outward = 0;     // fraction with n . (p - c) > 0
    double max_angle = 0;   // degrees, to the true normal up to sign
    double p999_angle = 0;  // 99.9th percentile of the angle, degrees
};

SphereCheck check_sphere(const prt::pre::PointCloud& cloud, std::array<double, 3> c) {
    SphereCheck r;
    std::vector<double> angles;
    std::size_t out = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto& p = cloud.positions[i];
        const double d[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
        const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        const auto& n = cloud.normals[i];
        const double cosine = (n.x * d[0] + n.y * d[1] + n.z * d[2]) / len;
        if (cosine > 0) ++out;
        angles.push_back(std::acos(std::min(1.0, std::fabs(cosine))) * 180.0 / k_pi);
    }
    std::sort(angles.begin(), angles.end());
    r.outward = static_cast<double>(out) / static_cast<double>(cloud.size());
    r.max_angle = angles.back();
    r.p999_angle = angles[static_cast<std::size_t>(0.999 * static_cast<double>(angles.size() - 1))];
    return r;
}

using NormalsTest = TempDirTest;  // every build estimates normals (our k-NN and PCA)

TEST_F(NormalsTest, SphereNormalsPointOutwardAndMatchTheTrueNormal) {
    // Far from the origin on purpose: PCA runs on centred float coordinates.
    const std::array<double, 3> centre{1e6, -3.0, 5.0};
    const auto file = write("sphere.xyz", xyz_text(fibonacci_sphere(20000, centre, 2.0)));
    Report report;
    const auto cloud = import(file, report);
    ASSERT_EQ(cloud.size(), 20000u);
    ASSERT_TRUE(cloud.has_normals());
    EXPECT_TRUE(cloud.flags & prt::pool::k_model_normals_estimated);
    EXPECT_TRUE(report.normals_estimated);
    const SphereCheck c = check_sphere(cloud, centre);
    EXPECT_GE(c.outward, 0.999);
    EXPECT_LT(c.p999_angle, 2.0);
    EXPECT_LT(c.max_angle, 5.0);
    EXPECT_EQ(report.components, 1u);
    EXPECT_EQ(report.ambiguous, 0u);
    std::printf("sphere: %.4f outward, max angle %.3f deg, 99.9%% within %.3f deg\n", c.outward, c.max_angle,
                c.p999_angle);
}

TEST_F(NormalsTest, NoisyRandomSphereStillOutward) {
    std::mt19937_64 rng(3);
    std::normal_distribution<double> gauss(0.0, 1.0);
    std::vector<std::array<double, 3>> pts;
    for (int i = 0; i < 30000; ++i) {
        double v[3] = {gauss(rng), gauss(rng), gauss(rng)};
        const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        const double r = 1.0 + 0.002 * gauss(rng);  // 0.2 % radial noise
        pts.push_back({r * v[0] / len, r * v[1] / len, r * v[2] / len});
    }
    const auto file = write("noisy.xyz", xyz_text(pts));
    Report report;
    const auto cloud = import(file, report);
    const SphereCheck c = check_sphere(cloud, {0, 0, 0});
    EXPECT_GE(c.outward, 0.999);
    EXPECT_LT(c.p999_angle, 10.0);
    std::printf("noisy sphere: %.5f outward, 99.9%% within %.3f deg, %llu ambiguous\n", c.outward,
                c.p999_angle, static_cast<unsigned long long>(report.ambiguous));
}

TEST_F(NormalsTest, TwoSpheresAreTwoComponentsBothOutward) {
    auto a = fibonacci_sphere(4000, {0, 0, 0}, 1.0);
    const auto b = fibonacci_sphere(4000, {10, 0, -3}, 0.5);
    a.insert(a.end(), b.begin(), b.end());
    const auto file = write("two.xyz", xyz_text(a));
    Report report;
    auto cloud = import(file, report);
    EXPECT_EQ(report.components, 2u);
    prt::pre::PointCloud first, second;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        auto& part = cloud.positions[i][0] < 5 ? first : second;
        part.positions.push_back(cloud.positions[i]);
        part.normals.push_back(cloud.normals[i]);
    }
    EXPECT_GE(check_sphere(first, {0, 0, 0}).outward, 0.999);
    EXPECT_GE(check_sphere(second, {10, 0, -3}).outward, 0.999);
}

TEST_F(NormalsTest, SensorOrientsTowardTheScanner) {
    // A wavy height field z = 0.1 sin(x) cos(y) seen from a sensor high above: normals face up.
    std::vector<std::array<double, 3>> pts;
    for (int i = 0; i < 100; ++i)
        for (int j = 0; j < 100; ++j) {
            const double x = i * 0.05, y = j * 0.05;
            pts.push_back({x, y, 0.1 * std::sin(x) * std::cos(y)});
        }
    const auto file = write("terrain.xyz", xyz_text(pts));
    Options options;
    options.sensor = std::array<double, 3>{2.5, 2.5, 50.0};
    Report report;
    const auto cloud = import(file, report, options);
    // A perfectly regular grid: the statistical outlier test (PCL's mean + 8 std) may take its 4
    // corners, whose neighbours are farthest; nothing else.
    ASSERT_EQ(cloud.size() + report.outliers.removed, 10000u);
    EXPECT_LE(report.outliers.removed, 4u);
    EXPECT_TRUE(report.oriented_to_sensor);
    std::size_t up = 0;
    for (const auto& n : cloud.normals) up += n.z > 0.9f;
    EXPECT_EQ(up, cloud.size());
    EXPECT_EQ(report.ambiguous, 0u);

    // The same surface seen from below: every normal flips.
    options.sensor = std::array<double, 3>{2.5, 2.5, -50.0};
    Report below;
    const auto flipped = import(file, below, options);
    std::size_t down = 0;
    for (const auto& n : flipped.normals) down += n.z < -0.9f;
    EXPECT_EQ(down, flipped.size());
}

TEST_F(NormalsTest, EstimateReplacesFileNormals) {
    // Wrong normals in the file (+x everywhere on a sphere); --normals estimate ignores them.
    std::string text;
    char buf[128];
    for (const auto& p : fibonacci_sphere(3000, {0, 0, 0}, 1.0)) {
        std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g 1 0 0\n", p[0], p[1], p[2]);
        text += buf;
    }
    const auto file = write("wrong.xyz", text);
    Options options;
    options.normals = prt::pre::import::NormalsMode::estimate;
    Report report;
    const auto cloud = import(file, report, options);
    EXPECT_TRUE(cloud.flags & prt::pool::k_model_normals_estimated);
    EXPECT_GE(check_sphere(cloud, {0, 0, 0}).outward, 0.999);

    // auto keeps them (and does not set the flag).
    Report kept;
    const auto original = import(file, kept);
    EXPECT_FALSE(original.flags & prt::pool::k_model_normals_estimated);
    EXPECT_FLOAT_EQ(original.normals[0].x, 1.f);
}

TEST_F(NormalsTest, DegenerateNeighbourhoodsAreDroppedAndCounted) {
    // 40 points on a line plus a plane patch: PCA on collinear neighbourhoods gives no plane.
    std::vector<std::array<double, 3>> pts;
    for (int i = 0; i < 40; ++i) pts.push_back({100.0 + i, 0, 0});
    for (int i = 0; i < 30; ++i)
        for (int j = 0; j < 30; ++j) pts.push_back({i * 0.1, j * 0.1, 0});
    const auto file = write("line.xyz", xyz_text(pts));
    Report report;
    Options keep_outliers;  // the line's points are far apart: outliers by default
    keep_outliers.outliers.enabled = false;
    const auto cloud = import(file, report, keep_outliers);
    // The line's neighbourhoods are collinear: no normal (dropped, counted); the plane's points
    // must all survive with normals along z.
    EXPECT_EQ(report.estimate_failed, 40u);
    EXPECT_EQ(cloud.size() + report.estimate_failed, pts.size());
    std::size_t along_z = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (cloud.positions[i][0] < 50) along_z += std::fabs(cloud.normals[i].z) > 0.99f;
    EXPECT_EQ(along_z, 900u);
}

// ---- orientation alone: brute-force k-NN graph, normals with random signs --------------

prt::pre::import::KnnGraph brute_force_knn(const std::vector<std::array<double, 3>>& p, std::uint32_t k) {
    prt::pre::import::KnnGraph g;
    g.k = k;
    g.neighbours.assign(p.size() * k, prt::pre::import::k_no_neighbour);
    for (std::size_t i = 0; i < p.size(); ++i) {
        std::vector<std::pair<double, std::uint32_t>> d;
        for (std::size_t j = 0; j < p.size(); ++j) {
            if (j == i) continue;
            const double dx = p[i][0] - p[j][0], dy = p[i][1] - p[j][1], dz = p[i][2] - p[j][2];
            d.push_back({dx * dx + dy * dy + dz * dz, static_cast<std::uint32_t>(j)});
        }
        std::partial_sort(d.begin(), d.begin() + k, d.end());
        for (std::uint32_t m = 0; m < k; ++m) g.neighbours[i * k + m] = d[m].second;
    }
    return g;
}

TEST(Orientation, PropagationRecoversOutwardSignsOnASphere) {
    const auto pts = fibonacci_sphere(1500, {0, 0, 0}, 1.0);
    std::vector<prt::pool::Float3> normals;
    std::mt19937 rng(11);
    for (const auto& p : pts) {
        const float s = (rng() & 1) ? 1.f : -1.f;
        normals.push_back(
            {s * static_cast<float>(p[0]), s * static_cast<float>(p[1]), s * static_cast<float>(p[2])});
    }
    const auto graph = brute_force_knn(pts, 10);
    const auto stats = prt::pre::import::orient_by_propagation(pts, normals, graph, true);
    EXPECT_EQ(stats.components, 1u);
    EXPECT_EQ(stats.ambiguous, 0u);
    for (std::size_t i = 0; i < pts.size(); ++i)
        EXPECT_GT(normals[i].x * pts[i][0] + normals[i].y * pts[i][1] + normals[i].z * pts[i][2], 0.0) << i;
}

TEST(Orientation, AmbiguousWhenEveryEarlierNeighbourIsPerpendicular) {
    // p0 is the top (seed, normal -z -> flipped to +z); p1's only neighbour is p0 and its normal is
    // horizontal: |n0 . n1| = 0 < 0.1, so p1 is ambiguous. p2 hangs off p1 with a parallel normal.
    const std::vector<std::array<double, 3>> pts = {{0, 0, 1}, {1, 0, 0}, {2, 0, 0}};
    std::vector<prt::pool::Float3> normals = {{0, 0, -1}, {1, 0, 0}, {-1, 0, 0}};
    prt::pre::import::KnnGraph g;
    g.k = 1;
    g.neighbours = {1, 0, 1};
    const auto stats = prt::pre::import::orient_by_propagation(pts, normals, g, true);
    EXPECT_EQ(stats.components, 1u);
    EXPECT_EQ(stats.ambiguous, 1u);
    EXPECT_EQ(normals[0].z, 1.f);
    EXPECT_EQ(normals[2].x, normals[1].x);  // consistent with its parent
}

TEST(Orientation, EachComponentGetsItsOwnSeed) {
    // Two far-apart clusters: the lower one's seed is its own top point, oriented +z.
    const std::vector<std::array<double, 3>> pts = {{0, 0, 10}, {0.1, 0, 10}, {0, 0, -10}, {0.1, 0, -10}};
    std::vector<prt::pool::Float3> normals = {{0, 0, -1}, {0, 0, 1}, {0, 0, -1}, {0, 0, -1}};
    prt::pre::import::KnnGraph g;
    g.k = 1;
    g.neighbours = {1, 0, 3, 2};
    const auto stats = prt::pre::import::orient_by_propagation(pts, normals, g, true);
    EXPECT_EQ(stats.components, 2u);
    for (const auto& n : normals) EXPECT_EQ(n.z, 1.f);
}

TEST(Orientation, InvalidNormalsAreSkipped) {
    const std::vector<std::array<double, 3>> pts = {{0, 0, 1}, {1, 0, 0}};
    std::vector<prt::pool::Float3> normals = {{0, 0, 1}, {NAN, 0, 0}};
    prt::pre::import::KnnGraph g;
    g.k = 1;
    g.neighbours = {1, 0};
    const auto stats = prt::pre::import::orient_by_propagation(pts, normals, g, true);
    EXPECT_EQ(stats.skipped, 1u);
    EXPECT_EQ(stats.components, 1u);
}

}  // namespace
