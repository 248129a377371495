// prt-radii's GPU path (runtime/cuda/src/knn.cu) against the CPU kd-tree, bit for bit: every radius
// and every statistic, on clouds made to break an approximate or tie-blind search (exact
// duplicates, a lattice where most neighbour distances are equal, points on a line and in a plane,
// a far outlier, n = k + 1, a cloud of several tree levels), for every clamp scope and k up to the
// GPU's 32. The CPU path is itself checked against a brute-force search in radii_test.cpp.
// Label gpu: skips with the reason where no CUDA device is usable.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>

#include "prt/error.h"
#ifdef PRT_HAVE_CUDA
#include "prt/cuda/knn_cuda.h"
#endif
#include "radii.h"
#include "splat_test_data.h"

namespace {

using prt::pool::Float3;

std::vector<Float3> mixed_points() {
    std::vector<Float3> p = prt::test::sphere_points(3000, 31).positions;
    std::mt19937_64 rng(32);
    std::uniform_real_distribution<float> u(-0.1f, 0.1f);
    for (int i = 0; i < 800; ++i) p.push_back({2 + u(rng), u(rng), u(rng)});
    for (int i = 0; i < 40; ++i) p.push_back(p[i * 7]);  // coincident points: distance 0
    for (int i = 0; i < 6; ++i) p.push_back(p[100]);     // more coincident than small k
    p.push_back({50, 50, 50});                           // an outlier the clamps act on
    return p;
}

/// An integer lattice, shuffled: most of a point's neighbours tie in distance, so the index
/// tie-break decides which k enter (and so the local clamp's medians).
std::vector<Float3> lattice_points(int side) {
    std::vector<Float3> p;
    for (int z = 0; z < side; ++z)
        for (int y = 0; y < side; ++y)
            for (int x = 0; x < side; ++x) p.push_back({float(x) * 0.5f, float(y) * 0.5f, float(z) * 0.5f});
    std::shuffle(p.begin(), p.end(), std::mt19937_64(33));
    return p;
}

std::vector<Float3> line_points(std::size_t n) {
    std::vector<Float3> p;
    std::mt19937_64 rng(34);
    std::uniform_real_distribution<float> u(0, 1);
    for (std::size_t i = 0; i < n; ++i) p.push_back({u(rng), 0.25f, -3.0f});
    return p;
}

std::vector<Float3> plane_points(std::size_t n) {
    std::vector<Float3> p;
    std::mt19937_64 rng(35);
    std::uniform_real_distribution<float> u(-10, 10);
    for (std::size_t i = 0; i < n; ++i) p.push_back({u(rng), u(rng), 1.5f});
    return p;
}

bool usable(std::string& why) {
    try {
        prt::pre::resolve_radii_backend("cuda", 1000, 9, 1);
        return true;
    } catch (const prt::Error& e) {
        why = e.what();
        return false;
    }
}

void expect_same(const std::vector<Float3>& p, std::uint32_t k, float factor, prt::pre::ClampScope scope) {
    SCOPED_TRACE("n = " + std::to_string(p.size()) + ", k = " + std::to_string(k) + ", factor " +
                 std::to_string(factor) + ", scope " + prt::pre::clamp_scope_name(scope));
    prt::pre::RadiiParams params;
    params.k = k;
    params.clamp_factor = factor;
    params.scope = scope;
    params.threads = 2;
    prt::pre::RadiiStats sc, sg;
    const std::vector<float> cpu = prt::pre::compute_radii(p, params, &sc);
    params.backend = "cuda";
    const std::vector<float> gpu = prt::pre::compute_radii(p, params, &sg);
    ASSERT_EQ(sg.backend, "cuda");
    ASSERT_EQ(cpu.size(), gpu.size());
    std::size_t differ = 0, first = 0;
    for (std::size_t i = 0; i < cpu.size(); ++i)
        if (std::memcmp(&cpu[i], &gpu[i], sizeof(float)) != 0 && differ++ == 0) first = i;
    ASSERT_EQ(differ, 0u) << "first at point " << first << ": CPU " << cpu[first] << ", GPU " << gpu[first];
    EXPECT_EQ(sc.points, sg.points);
    EXPECT_EQ(sc.clamped, sg.clamped);
    EXPECT_EQ(sc.zero, sg.zero);
    EXPECT_EQ(sc.raw_median, sg.raw_median);
    EXPECT_EQ(sc.clamp_limit, sg.clamp_limit);
    EXPECT_EQ(sc.min, sg.min);
    EXPECT_EQ(sc.median, sg.median);
    EXPECT_EQ(sc.mean, sg.mean);
    EXPECT_EQ(sc.max, sg.max);
}

TEST(KnnRadiiGpu, EqualTheCpuOnEveryCloudScopeAndK) {
    std::string why;
    if (!usable(why)) GTEST_SKIP() << why;
    const std::vector<Float3> mixed = mixed_points();
    for (const std::uint32_t k : {1u, 2u, 8u, 9u, 16u, 17u, 32u}) {
        expect_same(mixed, k, 3.0f, prt::pre::ClampScope::local);
        expect_same(mixed, k, 3.0f, prt::pre::ClampScope::global);
        expect_same(mixed, k, 0.0f, prt::pre::ClampScope::local);
    }
    const std::vector<Float3> lattice = lattice_points(24);
    for (const std::uint32_t k : {6u, 9u, 18u, 26u}) {
        expect_same(lattice, k, 1.0f, prt::pre::ClampScope::local);
        expect_same(lattice, k, 3.0f, prt::pre::ClampScope::global);
    }
    expect_same(line_points(5000), 9, 3.0f, prt::pre::ClampScope::local);
    expect_same(plane_points(20000), 9, 1.2f, prt::pre::ClampScope::local);
    for (const std::uint32_t k : {1u, 9u, 32u}) {  // n = k + 1: the tree is one leaf or two
        std::vector<Float3> tiny(mixed.begin(), mixed.begin() + k + 1);
        expect_same(tiny, k, 3.0f, prt::pre::ClampScope::local);
    }
}

TEST(KnnRadiiGpu, EqualTheCpuOnAMillionScanLikePoints) {
    std::string why;
    if (!usable(why)) GTEST_SKIP() << why;
    // A noisy sphere of 1M points (2^16 leaves, an odd count of the last leaf) and an even count.
    std::vector<Float3> p = prt::test::sphere_points(1000003, 36).positions;
    std::mt19937_64 rng(37);
    std::normal_distribution<float> noise(0.0f, 2e-4f);
    for (Float3& q : p) q.x += noise(rng), q.y += noise(rng), q.z += noise(rng);
    expect_same(p, 9, 3.0f, prt::pre::ClampScope::local);
    p.pop_back();
    expect_same(p, 9, 3.0f, prt::pre::ClampScope::global);
}

#ifdef PRT_HAVE_CUDA
// The local clamp reads the neighbours the search stored where the device has the memory (every
// test above), else searches them again: both ways give the same radii and the same count, on the
// lattice whose ties the index order breaks and on clouds of one and several launches (2^22
// queries each) for each register size of the search (k <= 8, 16, 32).
TEST(KnnRadiiGpu, StoredNeighboursClampAsASecondSearchDoes) {
    std::string why;
    if (!usable(why)) GTEST_SKIP() << why;
    using prt::cuda::KnnClamp;
    using prt::cuda::KnnNeighbours;
    std::vector<Float3> big = prt::test::sphere_points(4500000, 39).positions;
    std::mt19937_64 rng(40);
    std::normal_distribution<float> noise(0.0f, 5e-4f);
    for (Float3& q : big) q.x += noise(rng), q.y += noise(rng), q.z += noise(rng);
    const std::vector<Float3> lattice = lattice_points(20), mixed = mixed_points();
    for (const std::vector<Float3>* cloud :
         std::initializer_list<const std::vector<Float3>*>{&lattice, &mixed, &big})
        for (const std::uint32_t k : {5u, 9u, 17u, 32u}) {
            if (cloud == &big && k != 9u) continue;
            SCOPED_TRACE("n = " + std::to_string(cloud->size()) + ", k = " + std::to_string(k));
            const std::span<const float> xyz(reinterpret_cast<const float*>(cloud->data()),
                                             3 * cloud->size());
            std::vector<float> stored(cloud->size()), searched(cloud->size());
            const prt::cuda::KnnRadiiResult a = prt::cuda::knn_radii_cuda(
                xyz, k, KnnClamp::local, 1.1f, stored, {}, KnnNeighbours::stored_if_free);
            const prt::cuda::KnnRadiiResult b = prt::cuda::knn_radii_cuda(
                xyz, k, KnnClamp::local, 1.1f, searched, {}, KnnNeighbours::searched_again);
            EXPECT_TRUE(a.neighbours_stored);
            EXPECT_FALSE(b.neighbours_stored);
            if (cloud != &lattice) {
                EXPECT_GT(a.clamped, 0u);  // the outlier; the noise
            }
            EXPECT_EQ(a.clamped, b.clamped);
            EXPECT_EQ(a.median, b.median);
            EXPECT_EQ(0, std::memcmp(stored.data(), searched.data(), stored.size() * sizeof(float)));
        }
}
#endif

TEST(KnnRadiiGpu, NamesTheFirstNonFinitePointAsTheCpuDoes) {
    std::string why;
    if (!usable(why)) GTEST_SKIP() << why;
    std::vector<Float3> p = prt::test::sphere_points(5000, 38).positions;
    p[4321].y = std::nanf("");
    p[4400].z = INFINITY;
    prt::pre::RadiiParams params;
    std::string cpu, gpu;
    try {
        prt::pre::compute_radii(p, params);
    } catch (const prt::Error& e) {
        cpu = e.what();
    }
    params.backend = "cuda";
    try {
        prt::pre::compute_radii(p, params);
    } catch (const prt::Error& e) {
        gpu = e.what();
    }
    EXPECT_NE(cpu.find("point 4321 has a non-finite position"), std::string::npos) << cpu;
    EXPECT_EQ(cpu, gpu);
}

TEST(KnnRadiiGpu, AutoPicksTheGpuAndFallsBackAboveItsKAndBelowItsSize) {
    std::string why;
    if (!usable(why)) GTEST_SKIP() << why;
    EXPECT_EQ(prt::pre::resolve_radii_backend("auto", 1000000, 9, 1), "cuda");
    EXPECT_EQ(prt::pre::resolve_radii_backend("auto", 1000000, 33, 1, &why), "cpu");
    EXPECT_NE(why.find("k = 33"), std::string::npos) << why;
    EXPECT_THROW(prt::pre::resolve_radii_backend("cuda", 1000, 33, 1), prt::Error);
    EXPECT_EQ(prt::pre::resolve_radii_backend("auto", 1000, 9, 1), "cpu");   // small: the CPU is as fast
    EXPECT_EQ(prt::pre::resolve_radii_backend("cuda", 1000, 9, 1), "cuda");  // unless asked
}

}  // namespace
