// The import's k-NN (kd-tree, knn.h) and what it serves (neighbours.h): exact neighbours against
// brute force; outlier removal against a brute-force transcription of PCL's StatisticalOutlierRemoval
// and RadiusOutlierRemoval rules; the graph after removal against brute force over the survivors;
// PCA normals against analytic planes; the default settings on synthetic scans with outliers.
#include "knn.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "import_test_util.h"
#include "neighbours.h"
#include "scan_reference.h"

namespace {

using namespace prt_import_test;
using prt::pre::PointCloud;
using prt::pre::import::KdTree;
using prt::pre::import::KnnGraph;
using prt::pre::import::OutlierParams;
using prt::pre::import::OutlierReport;
using Vec3 = std::array<double, 3>;

double dist2(const Vec3& a, const Vec3& b) {
    return (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]);
}

/// Brute force: the k nearest other points (not excluded), by (distance, index).
std::vector<std::pair<double, std::uint32_t>> brute(const std::vector<Vec3>& p, std::size_t i, std::size_t k,
                                                    const std::vector<std::uint8_t>* excluded = nullptr) {
    std::vector<std::pair<double, std::uint32_t>> d;
    for (std::size_t j = 0; j < p.size(); ++j)
        if (j != i && !(excluded && (*excluded)[j]))
            d.push_back({dist2(p[i], p[j]), static_cast<std::uint32_t>(j)});
    std::sort(d.begin(), d.end());
    d.resize(std::min(k, d.size()));
    return d;
}

std::vector<Vec3> random_points(std::size_t n, std::uint64_t seed, Vec3 offset = {0, 0, 0},
                                double scale = 1) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<Vec3> p(n);
    for (auto& q : p)
        q = {offset[0] + scale * u(rng), offset[1] + scale * u(rng), offset[2] + scale * 0.2 * u(rng)};
    return p;
}

TEST(KdTree, MatchesBruteForce) {
    // Far from the origin (float offsets from the centre), with exact duplicates and a tight cluster.
    auto p = random_points(3000, 1, {1e6, -2e5, 3}, 2.0);
    for (int i = 0; i < 50; ++i) p.push_back(p[static_cast<std::size_t>(i) * 7]);
    for (int i = 0; i < 40; ++i) p.push_back({1e6 + 1e-3 * i, -2e5, 3});
    const KdTree tree(p);
    ASSERT_EQ(tree.size(), p.size());
    for (const std::uint32_t k : {1u, 5u, 16u}) {
        std::size_t mismatches = 0;
        tree.for_each(k, 2,
                      [&](std::uint32_t i, const std::uint32_t* index, const float* d2, std::uint32_t found) {
                          const auto b = brute(p, i, k);
                          if (found != b.size()) ++mismatches;
                          for (std::uint32_t j = 0; j < found && j < b.size(); ++j) {
                              // float offsets: the j-th distance agrees to float precision; ties may swap
                              // indices
                              const double want = std::sqrt(b[j].first), got = std::sqrt(double(d2[j]));
                              if (std::fabs(want - got) > 1e-6 * 2.0 + 1e-7 * want) ++mismatches;
                              if (index[j] == i) ++mismatches;
                              if (std::fabs(std::sqrt(dist2(p[i], p[index[j]])) - want) > 1e-5) ++mismatches;
                          }
                      });
        EXPECT_EQ(mismatches, 0u) << "k=" << k;
    }
}

TEST(KdTree, FewerPointsThanKAndExclusion) {
    const std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {0, 0, 3}};
    const KdTree tree(p);
    std::uint32_t index[8];
    float d2[8];
    EXPECT_EQ(tree.nearest(0, 8, nullptr, index, d2), 3u);
    EXPECT_EQ(index[0], 1u);
    EXPECT_EQ(index[1], 2u);
    EXPECT_EQ(index[2], 3u);
    EXPECT_FLOAT_EQ(d2[2], 9.f);
    const std::vector<std::uint8_t> excluded = {0, 1, 0, 0};
    EXPECT_EQ(tree.nearest(0, 2, excluded.data(), index, d2), 2u);
    EXPECT_EQ(index[0], 2u);
    EXPECT_EQ(index[1], 3u);
    // One point: no neighbours at all.
    const KdTree single(std::vector<Vec3>{{5, 5, 5}});
    EXPECT_EQ(single.nearest(0, 3, nullptr, index, d2), 0u);

    // Larger set with an exclusion mask, against brute force.
    const auto q = random_points(2000, 4);
    std::vector<std::uint8_t> mask(q.size());
    for (std::size_t i = 0; i < q.size(); ++i) mask[i] = i % 3 == 0;
    const KdTree t2(q);
    for (std::size_t i = 0; i < q.size(); i += 37) {
        std::uint32_t idx[10];
        float dd[10];
        const std::uint32_t found = t2.nearest(static_cast<std::uint32_t>(i), 10, mask.data(), idx, dd);
        const auto b = brute(q, i, 10, &mask);
        ASSERT_EQ(found, b.size());
        for (std::uint32_t j = 0; j < found; ++j) EXPECT_NEAR(std::sqrt(dd[j]), std::sqrt(b[j].first), 1e-6);
    }
}

// ---- outliers: PCL's rules transcribed by brute force ---------------------------------------------

struct Expected {
    std::vector<std::uint8_t> statistical, radius;
};

/// PCL StatisticalOutlierRemoval (mean of the k nearest distances, sample std over all points,
/// outlier above mean + ratio x std) and RadiusOutlierRemoval (fewer than m others within r), with
/// r = factor x the median of the per-point mean distances.
Expected brute_outliers(const std::vector<Vec3>& p, const OutlierParams& params) {
    const std::size_t n = p.size();
    std::vector<double> mean(n);
    for (std::size_t i = 0; i < n; ++i) {
        const auto b = brute(p, i, params.k);
        double s = 0;
        for (const auto& [d, j] : b) s += std::sqrt(d);
        mean[i] = s / double(b.size());
    }
    double sum = 0, sum2 = 0;
    for (const double m : mean) {
        sum += m;
        sum2 += m * m;
    }
    const double mu = sum / double(n);
    const double sd = std::sqrt((sum2 - sum * sum / double(n)) / double(n - 1));
    std::vector<double> sorted(mean);
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>((n - 1) / 2), sorted.end());
    const double radius = params.radius_factor * sorted[(n - 1) / 2];
    Expected e;
    e.statistical.resize(n);
    e.radius.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        e.statistical[i] = mean[i] > mu + params.std_ratio * sd;
        std::uint32_t within = 0;
        for (std::size_t j = 0; j < n; ++j) within += j != i && std::sqrt(dist2(p[i], p[j])) <= radius;
        e.radius[i] = within < params.min_neighbours;
    }
    return e;
}

TEST(Outliers, StatisticalAndRadiusFollowPclsRules) {
    // A noisy plane patch with isolated points and a clump of 3 points above it.
    auto p = random_points(1500, 7);
    std::mt19937_64 rng(8);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int i = 0; i < 12; ++i) p.push_back({u(rng), u(rng), 0.5 + 0.5 * std::fabs(u(rng))});
    for (int i = 0; i < 3; ++i) p.push_back({0.3 + 0.002 * i, 0.3, 1.5});
    for (const double ratio : {1.0, 3.0}) {
        OutlierParams params;
        params.k = 6;
        params.std_ratio = ratio;
        params.radius_factor = 2.5;
        params.min_neighbours = 3;
        const Expected e = brute_outliers(p, params);
        // Each rule alone, then both.
        for (int which = 0; which < 3; ++which) {
            OutlierParams q = params;
            if (which == 0) q.radius_factor = 0;
            if (which == 1) q.std_ratio = 0;
            PointCloud cloud;
            cloud.positions = p;
            cloud.intensities.resize(p.size());
            for (std::size_t i = 0; i < p.size(); ++i) cloud.intensities[i] = static_cast<float>(i);
            OutlierReport report;
            prt::pre::import::outliers_and_graph(cloud, q, 0, nullptr, report, true);
            std::vector<std::uint8_t> removed(p.size(), 1);
            for (const float f : cloud.intensities) removed[static_cast<std::size_t>(f)] = 0;
            std::size_t disagreements = 0, expected_removed = 0;
            for (std::size_t i = 0; i < p.size(); ++i) {
                const bool want = (which != 1 && e.statistical[i]) || (which != 0 && e.radius[i]);
                expected_removed += want;
                disagreements += want != (removed[i] != 0);
            }
            EXPECT_EQ(disagreements, 0u) << "ratio " << ratio << " test " << which;
            EXPECT_EQ(report.removed, expected_removed);
            EXPECT_EQ(report.input, p.size());
            EXPECT_TRUE(report.ran);
            if (which == 2) {
                EXPECT_GE(expected_removed, 12u);  // the isolated points at least
            }
        }
    }
}

TEST(Outliers, RangeFromTheScannerScalesBothTests) {
    // A scanner at the origin 1 above a floor, sampling it at a fixed angular step: the spacing
    // grows with range. Six points float 0.3 from the scanner, 0.06 apart: sparse for their range
    // (the floor below is sampled at about 0.05 there) yet denser than the far floor.
    std::vector<Vec3> p;
    const double step = 0.05;  // radians
    for (double az = 0; az < 2 * M_PI; az += step)
        for (double el = -M_PI / 2 + 0.05; el < -0.12; el += step)
            p.push_back({std::cos(el) * std::cos(az) / -std::tan(el), -1.0,
                         std::cos(el) * std::sin(az) / -std::tan(el)});
    const std::size_t floor = p.size();
    for (int i = 0; i < 6; ++i) p.push_back({0.3, -0.06 * i, 0.0});
    OutlierParams params;  // the defaults
    auto run = [&](bool with_sensor, std::vector<std::uint8_t>& removed) {
        PointCloud cloud;
        cloud.positions = p;
        cloud.intensities.resize(p.size());
        for (std::size_t i = 0; i < p.size(); ++i) cloud.intensities[i] = static_cast<float>(i);
        OutlierParams q = params;
        if (with_sensor) q.sensor = Vec3{0, 0, 0};
        OutlierReport report;
        prt::pre::import::outliers_and_graph(cloud, q, 0, nullptr, report, true);
        removed.assign(p.size(), 1);
        for (const float f : cloud.intensities) removed[static_cast<std::size_t>(f)] = 0;
        EXPECT_EQ(report.range_scaled, with_sensor);
        return report;
    };
    std::vector<std::uint8_t> plain, scaled;
    run(false, plain);
    run(true, scaled);
    int floaters_plain = 0, floaters_scaled = 0, floor_scaled = 0;
    for (std::size_t i = floor; i < p.size(); ++i) floaters_plain += plain[i], floaters_scaled += scaled[i];
    for (std::size_t i = 0; i < floor; ++i) floor_scaled += scaled[i];
    EXPECT_LT(floaters_plain, 3) << "without the range, most floaters look denser than the far floor";
    EXPECT_EQ(floaters_scaled, 6) << "relative to their range they are isolated";
    EXPECT_LE(floor_scaled, int(floor / 1000)) << "the floor stays";
    // The brute-force rule with distances divided by the range (times the median range).
    std::vector<double> range(p.size()), mean(p.size()), mth(p.size());
    for (std::size_t i = 0; i < p.size(); ++i) range[i] = std::sqrt(dist2(p[i], {0, 0, 0}));
    std::vector<double> sr(range);
    std::nth_element(sr.begin(), sr.begin() + static_cast<std::ptrdiff_t>((sr.size() - 1) / 2), sr.end());
    const double median_range = sr[(sr.size() - 1) / 2];
    for (std::size_t i = 0; i < p.size(); ++i) {
        const auto b = brute(p, i, params.k);
        double sum = 0;
        for (const auto& [d, j] : b) sum += std::sqrt(d);
        mean[i] = sum / double(b.size()) * median_range / range[i];
        mth[i] = std::sqrt(b[params.min_neighbours - 1].first) * median_range / range[i];
    }
    double sum = 0, sum2 = 0;
    for (double m : mean) sum += m, sum2 += m * m;
    const double mu = sum / double(p.size()),
                 sd = std::sqrt((sum2 - sum * sum / double(p.size())) / double(p.size() - 1));
    std::vector<double> sm(mean);
    std::nth_element(sm.begin(), sm.begin() + static_cast<std::ptrdiff_t>((sm.size() - 1) / 2), sm.end());
    const double radius = params.radius_factor * sm[(sm.size() - 1) / 2];
    std::size_t disagreements = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        const bool want = mean[i] > mu + params.std_ratio * sd || mth[i] > radius;
        disagreements += want != (scaled[i] != 0);
    }
    EXPECT_LE(disagreements, 2u) << "float rounding of the per-point distances at the thresholds only";
}

TEST(Outliers, GraphAfterRemovalIsTheSurvivorsKnn) {
    auto p = random_points(1200, 11);
    for (int i = 0; i < 20; ++i) p.push_back({-1 + 0.1 * i, 0.5, 3.0 + 0.37 * i});  // far off the patch
    PointCloud cloud;
    cloud.positions = p;
    OutlierParams params;
    KnnGraph graph;
    OutlierReport report;
    prt::pre::import::outliers_and_graph(cloud, params, 10, &graph, report, true);
    EXPECT_GE(report.removed, 20u);
    ASSERT_EQ(cloud.size() + report.removed, 1220u);
    for (const auto& q : cloud.positions) EXPECT_LT(q[2], 1.0);  // every far point went
    ASSERT_EQ(graph.k, 10u);
    ASSERT_EQ(graph.neighbours.size(), cloud.size() * 10u);
    std::size_t bad = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto b = brute(cloud.positions, i, 10);
        for (std::size_t j = 0; j < 10; ++j) {
            const std::uint32_t m = graph.neighbours[i * 10 + j];
            if (m >= cloud.size() ||
                std::fabs(dist2(cloud.positions[i], cloud.positions[m]) - b[j].first) > 1e-9)
                ++bad;
        }
    }
    EXPECT_EQ(bad, 0u);
}

TEST(Outliers, SkippedWhenDisabledOrTooFew) {
    PointCloud cloud;
    cloud.positions = random_points(100, 3);
    cloud.positions.push_back({0, 0, 50});
    OutlierParams off;
    off.enabled = false;
    OutlierReport report;
    prt::pre::import::outliers_and_graph(cloud, off, 0, nullptr, report, true);
    EXPECT_FALSE(report.ran);
    EXPECT_EQ(cloud.size(), 101u);
    EXPECT_NE(report.summary().find("--keep-outliers"), std::string::npos);
    PointCloud few;
    few.positions = random_points(5, 3);
    OutlierParams on;
    prt::pre::import::outliers_and_graph(few, on, 0, nullptr, report, true);
    EXPECT_FALSE(report.ran);
    EXPECT_EQ(few.size(), 5u);
    EXPECT_NE(report.summary().find("need more than --outlier-k"), std::string::npos) << report.summary();
}

/// The defaults on synthetic scans: 1 % of the points moved along the line of sight by 5-25 % of
/// the model size must go (>= 90 %), good points must stay (< 0.5 % removed).
void check_defaults_on(const std::vector<Vec3>& scan, const prt::pool::Sensor& sensor, const char* what) {
    std::vector<Vec3> pts = scan;
    const auto moved = prt_scan_ref::displace_outliers(pts, sensor, prt_scan_ref::diagonal(scan), 0.01, 99);
    PointCloud cloud;
    cloud.positions = pts;
    cloud.intensities.resize(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) cloud.intensities[i] = moved[i];
    OutlierReport report;
    prt::pre::import::outliers_and_graph(cloud, OutlierParams{}, 0, nullptr, report, true);
    std::size_t bad = 0, good = 0, bad_left = 0, good_left = 0;
    for (const std::uint8_t m : moved) (m ? bad : good) += 1;
    for (const float f : cloud.intensities) (f > 0 ? bad_left : good_left) += 1;
    const double removed_bad = double(bad - bad_left) / double(bad);
    const double removed_good = double(good - good_left) / double(good);
    EXPECT_GE(removed_bad, 0.90) << what;
    EXPECT_LT(removed_good, 0.005) << what;
    std::printf("%s: %zu outliers, %.2f %% removed; %.3f %% of good points removed\n", what, bad,
                100 * removed_bad, 100 * removed_good);
}

TEST(Outliers, DefaultsOnSyntheticScans) {
    std::mt19937_64 rng(5);
    std::normal_distribution<double> g(0, 1);
    std::uniform_real_distribution<double> u(-1, 1);
    // The half of a unit sphere a sensor at (0, 0, 5) sees, sampled at random, with range noise.
    std::vector<Vec3> sphere;
    while (sphere.size() < 30000) {
        Vec3 v{g(rng), g(rng), g(rng)};
        const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        const Vec3 p{v[0] / l, v[1] / l, v[2] / l};
        if (p[2] * (5 - p[2]) - p[0] * p[0] - p[1] * p[1] <= 0) continue;  // n . (s - p) <= 0: unseen
        const double r = 1 + 0.001 * g(rng);
        sphere.push_back({r * p[0], r * p[1], r * p[2]});
    }
    check_defaults_on(sphere, {{0, 0, 5}, prt::pool::k_sensor_point, 0}, "sphere scan");
    // A plane seen from above, sampled at random.
    std::vector<Vec3> plane;
    for (int i = 0; i < 30000; ++i) plane.push_back({u(rng), u(rng), 0.002 * g(rng)});
    check_defaults_on(plane, {{0.2, 0.1, 3}, prt::pool::k_sensor_point, 0}, "plane scan");
    // The same plane as a far sensor sees it (a direction).
    check_defaults_on(plane, {{0.0, 0.6, 0.8}, prt::pool::k_sensor_direction, 0}, "plane, far sensor");
}

// ---- PCA normals ------------------------------------------------------------------------------------

TEST(PcaNormals, PlanesAndDegenerateNeighbourhoods) {
    // A tilted plane far from the origin: every normal parallel to the plane's.
    const Vec3 n{1 / std::sqrt(14.0), 2 / std::sqrt(14.0), 3 / std::sqrt(14.0)};
    const Vec3 a{2 / std::sqrt(5.0), -1 / std::sqrt(5.0), 0};
    const Vec3 b{n[1] * a[2] - n[2] * a[1], n[2] * a[0] - n[0] * a[2], n[0] * a[1] - n[1] * a[0]};
    std::mt19937_64 rng(2);
    std::uniform_real_distribution<double> u(-1, 1);
    PointCloud cloud;
    for (int i = 0; i < 2000; ++i) {
        const double s = u(rng), t = u(rng);
        cloud.positions.push_back(
            {1e5 + s * a[0] + t * b[0], -7 + s * a[1] + t * b[1], 3 + s * a[2] + t * b[2]});
    }
    // Plus 5 collinear points far away (a line: no plane) and 2 points alone.
    for (int i = 0; i < 5; ++i) cloud.positions.push_back({-50.0 + i, 0, 0});
    OutlierParams off;
    off.enabled = false;
    KnnGraph graph;
    OutlierReport report;
    prt::pre::import::outliers_and_graph(cloud, off, 4, &graph, report, true);
    const auto normals = prt::pre::import::pca_normals(cloud.positions, graph, 5, true);
    ASSERT_EQ(normals.size(), cloud.size());
    double worst = 1;
    for (std::size_t i = 0; i < 2000; ++i)
        worst = std::min(worst, std::fabs(normals[i].x * n[0] + normals[i].y * n[1] + normals[i].z * n[2]));
    EXPECT_GT(worst, 0.99999);
    for (std::size_t i = 2000; i < cloud.size(); ++i) EXPECT_TRUE(std::isnan(normals[i].x)) << i;
}

}  // namespace
