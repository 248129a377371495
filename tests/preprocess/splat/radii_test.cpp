// k-NN splat radii (thesis 3.1) against a brute-force O(n^2) computation in double.
#include "radii.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "prt/error.h"
#include "splat_test_data.h"

namespace {

using prt::pool::Float3;

std::vector<Float3> mixed_points() {
    // a sphere, a dense random blob, exact duplicates and a far outlier
    std::vector<Float3> p = prt::test::sphere_points(600, 21).positions;
    std::mt19937_64 rng(22);
    std::uniform_real_distribution<float> u(-0.1f, 0.1f);
    for (int i = 0; i < 200; ++i) p.push_back({2 + u(rng), u(rng), u(rng)});
    for (int i = 0; i < 12; ++i) p.push_back(p[i * 7]);  // coincident points count at distance 0
    p.push_back({50, 50, 50});
    return p;
}

TEST(KnnRadii, EqualBruteForce) {
    const std::vector<Float3> p = mixed_points();
    for (const std::uint32_t k : {1u, 9u, 20u}) {
        SCOPED_TRACE("k = " + std::to_string(k));
        const std::vector<double> expected = prt::test::brute_force_knn(p, k);
        const std::vector<float> got = prt::pre::knn_distances(p, k, 2);
        ASSERT_EQ(got.size(), p.size());
        for (std::size_t i = 0; i < p.size(); ++i)
            ASSERT_NEAR(got[i], expected[i], 1e-5 * expected[i] + 1e-7) << "point " << i;
    }
}

TEST(KnnRadii, BackendNames) {
    EXPECT_EQ(prt::pre::resolve_radii_backend("cpu", 1000, 9, 1), "cpu");
    EXPECT_THROW(prt::pre::resolve_radii_backend("gpu", 1000, 9, 1), prt::Error);
    std::string why;
    const std::string a = prt::pre::resolve_radii_backend("auto", 1000000, 9, 1, &why);
    if (a == "cpu")
        EXPECT_FALSE(why.empty());  // the reason the tool prints
    else
        EXPECT_EQ(a, "cuda");
    // a small model, or k above the GPU search's: auto always falls back, --backend cuda says why
    EXPECT_FALSE(prt::pre::radii_gpu_pays(99999, 1));
    EXPECT_TRUE(prt::pre::radii_gpu_pays(200000, 2));
    EXPECT_EQ(prt::pre::resolve_radii_backend("auto", 1000, 9, 1, &why), "cpu");
    EXPECT_NE(why.find("CPU is as fast"), std::string::npos) << why;
    EXPECT_EQ(prt::pre::resolve_radii_backend("auto", 1000000, 33, 1, &why), "cpu");
    try {
        prt::pre::resolve_radii_backend("cuda", 1000, 33, 1);
        FAIL() << "k = 33 on the GPU";
    } catch (const prt::Error& e) {
        EXPECT_NE(std::string(e.what()).find("--backend cuda"), std::string::npos) << e.what();
    }
}

TEST(KnnRadii, ThreadCountDoesNotChangeTheResult) {
    const std::vector<Float3> p = prt::test::sphere_points(20000, 23).positions;
    EXPECT_EQ(prt::pre::knn_distances(p, 9, 1), prt::pre::knn_distances(p, 9, 3));
}

TEST(KnnRadii, TooFewPointsIsAnError) {
    const std::vector<Float3> p = prt::test::sphere_points(9, 24).positions;
    EXPECT_THROW(prt::pre::knn_distances(p, 9, 1), prt::Error);
    EXPECT_NO_THROW(prt::pre::knn_distances(p, 8, 1));
    std::vector<Float3> bad = prt::test::sphere_points(20, 25).positions;
    bad[4].y = std::nanf("");
    EXPECT_THROW(prt::pre::knn_distances(bad, 9, 1), prt::Error);
}

TEST(KnnRadii, ClampRuleAndStatistics) {
    std::vector<float> r = {1, 2, 3, 4, 100, 0.5f, 2.5f};  // median 2.5
    prt::pre::RadiiStats stats;
    prt::pre::clamp_radii(r, 3.0f, stats);
    EXPECT_DOUBLE_EQ(stats.raw_median, 2.5);
    EXPECT_DOUBLE_EQ(stats.clamp_limit, 7.5);
    EXPECT_EQ(stats.clamped, 1u);
    EXPECT_FLOAT_EQ(r[4], 7.5f);
    EXPECT_FLOAT_EQ(r[3], 4.0f);
    EXPECT_DOUBLE_EQ(stats.min, 0.5);
    EXPECT_DOUBLE_EQ(stats.max, 7.5);
    EXPECT_NEAR(stats.mean, (1 + 2 + 3 + 4 + 7.5 + 0.5 + 2.5) / 7.0, 1e-12);
    EXPECT_DOUBLE_EQ(stats.median, 2.5);

    std::vector<float> with_zero = {4, 1, 3, 2, 0};  // median 2; the zero is counted
    prt::pre::clamp_radii(with_zero, 0.0f, stats);   // clamping off
    EXPECT_EQ(stats.clamped, 0u);
    EXPECT_EQ(stats.zero, 1u);
    EXPECT_DOUBLE_EQ(stats.median, 2.0);
    std::vector<float> four = {4, 1, 3, 2};
    prt::pre::clamp_radii(four, 1.0f, stats);  // median (2 + 3) / 2 = 2.5: the 3 and 4 clamp
    EXPECT_DOUBLE_EQ(stats.raw_median, 2.5);
    EXPECT_EQ(stats.clamped, 2u);
    EXPECT_FLOAT_EQ(four[0], 2.5f);
}

// The statistics sum in blocks of 2^20 radii, each from zero, the block sums in index order: the
// same bits on any thread count (the GPU and streamed paths take them the same way), over a model
// of several blocks whose last is short.
TEST(KnnRadii, StatisticsSumInBlocksWhateverTheThreads) {
    std::vector<float> r(9 * (std::size_t{1} << 20) + 12345);
    std::mt19937_64 rng(26);
    std::uniform_real_distribution<float> u(0.001f, 0.01f);
    for (float& v : r) v = u(rng);
    r[5] = 0;
    r[3000000] = 0.5f;
    double want = 0;
    for (std::size_t b = 0; b < r.size(); b += std::size_t{1} << 20) {
        double block = 0;
        for (std::size_t i = b; i < std::min(r.size(), b + (std::size_t{1} << 20)); ++i) block += r[i];
        want += block;
    }
    for (const unsigned threads : {1u, 3u, 0u}) {
        SCOPED_TRACE("threads " + std::to_string(threads));
        std::vector<float> copy = r;
        prt::pre::RadiiStats stats;
        prt::pre::clamp_radii(copy, 0.0f, stats, threads);
        EXPECT_EQ(stats.mean, want / double(r.size()));
        EXPECT_EQ(stats.zero, 1u);
        EXPECT_EQ(stats.min, 0.0);
        EXPECT_EQ(stats.max, 0.5);
    }
}

TEST(KnnRadii, ComputeRadiiClampsTheOutlierGlobally) {
    const std::vector<Float3> p = mixed_points();
    prt::pre::RadiiParams params;
    params.scope = prt::pre::ClampScope::global;
    prt::pre::RadiiStats stats;
    const std::vector<float> r = prt::pre::compute_radii(p, params, &stats);
    const std::vector<double> raw = prt::test::brute_force_knn(p, 9);
    std::vector<double> sorted = raw;
    std::sort(sorted.begin(), sorted.end());
    const double median = 0.5 * (sorted[(sorted.size() - 1) / 2] + sorted[sorted.size() / 2]);
    EXPECT_NEAR(stats.raw_median, median, 1e-5 * median);
    std::uint64_t expected_clamped = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        const double limit = 3.0 * median;
        if (raw[i] > limit * (1 + 1e-5)) {
            ++expected_clamped;
            EXPECT_NEAR(r[i], limit, 1e-5 * limit);
        } else if (raw[i] < limit * (1 - 1e-5)) {
            EXPECT_NEAR(r[i], raw[i], 1e-5 * raw[i] + 1e-7);
        }
    }
    EXPECT_GE(expected_clamped, 1u);  // at least the far outlier
    EXPECT_EQ(stats.clamped, expected_clamped);
}

/// Brute force: the indices of each point's k nearest other points (ties by index).
std::vector<std::vector<std::size_t>> brute_neighbours(const std::vector<Float3>& p, std::uint32_t k) {
    std::vector<std::vector<std::size_t>> out(p.size());
    for (std::size_t i = 0; i < p.size(); ++i) {
        std::vector<std::pair<double, std::size_t>> d;
        for (std::size_t j = 0; j < p.size(); ++j) {
            if (j == i) continue;
            const double x = double(p[i].x) - p[j].x, y = double(p[i].y) - p[j].y,
                         z = double(p[i].z) - p[j].z;
            d.push_back({x * x + y * y + z * z, j});
        }
        std::partial_sort(d.begin(), d.begin() + k, d.end());
        for (std::uint32_t t = 0; t < k; ++t) out[i].push_back(d[t].second);
    }
    return out;
}

TEST(KnnRadii, LocalClampKeepsSparseRegionsAndClampsIsolatedPoints) {
    // A dense square (spacing 0.01), a square 8 times sparser beside it, one point floating 1.0
    // above the dense one: the global rule clamps the whole sparse square, the local one only the
    // floating point.
    std::vector<Float3> p;
    for (int i = 0; i < 30; ++i)
        for (int j = 0; j < 30; ++j) p.push_back({0.01f * i + 0.001f * (j % 3), 0, 0.01f * j});
    for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 12; ++j) p.push_back({1 + 0.08f * i, 0, 0.08f * j + 0.004f * (i % 2)});
    p.push_back({0.15f, 1.0f, 0.15f});
    const std::uint32_t k = 9;
    const std::vector<double> raw = prt::test::brute_force_knn(p, k);
    const auto nb = brute_neighbours(p, k);
    prt::pre::RadiiParams params;  // local, factor 3
    prt::pre::RadiiStats stats;
    const std::vector<float> r = prt::pre::compute_radii(p, params, &stats);
    std::uint64_t expected = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        std::vector<double> v;
        for (std::size_t j : nb[i]) v.push_back(raw[j]);
        std::sort(v.begin(), v.end());
        const double limit = 3.0 * v[k / 2];
        if (raw[i] > limit * (1 + 1e-5)) {
            ++expected;
            EXPECT_NEAR(r[i], limit, 1e-5 * limit) << i;
        } else if (raw[i] < limit * (1 - 1e-5)) {
            EXPECT_NEAR(r[i], raw[i], 1e-5 * raw[i] + 1e-7) << i;
        }
    }
    EXPECT_EQ(stats.clamped, expected);
    EXPECT_LT(r.back(), 0.5 * raw.back()) << "the floating point is clamped";
    for (std::size_t i = 900; i < 900 + 144; ++i)
        EXPECT_NEAR(r[i], raw[i], 1e-5 * raw[i]) << "sparse point " << i;
    // the global rule clamps most of the sparse square
    params.scope = prt::pre::ClampScope::global;
    const std::vector<float> g = prt::pre::compute_radii(p, params, &stats);
    int sparse_clamped = 0;
    for (std::size_t i = 900; i < 900 + 144; ++i) sparse_clamped += g[i] < 0.99 * raw[i];
    EXPECT_GT(sparse_clamped, 100);
}

}  // namespace
