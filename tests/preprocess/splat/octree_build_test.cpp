// The splat octree builder (thesis 2.2, 3.2, 3.4) against brute force: layout, leaf ranges,
// replication into exactly the overlapped leaves, subdivision rule, deep trees, limits, pools.
#include "octree_build.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "octree_check.h"
#include "point_cloud.h"
#include "prt/formats/pool.h"
#include "splat_test_data.h"

namespace {

using prt::pre::build_octree;
using prt::pre::OctreeParams;
using prt::pre::OctreeStats;
using prt::test::SplatSet;

SplatSet sphere_with_knn_radii(std::size_t n, std::uint64_t seed, std::uint32_t k = 9) {
    SplatSet s = prt::test::sphere_points(n, seed);
    for (const double r : prt::test::brute_force_knn(s.positions, k)) s.radii.push_back(float(r));
    return s;
}

prt::test::CheckSummary build_and_check(const SplatSet& s, const OctreeParams& params,
                                        OctreeStats* stats_out = nullptr) {
    OctreeStats stats;
    const prt::pre::SplatOctree octree = build_octree(s.positions, s.normals, s.radii, params, &stats);
    auto summary = prt::test::check_octree(octree, s.positions, s.normals, s.radii, params);
    EXPECT_EQ(stats.nodes, octree.nodes.size());
    EXPECT_EQ(stats.stored_splats, octree.splats.size());
    EXPECT_EQ(stats.filled_leaves + 1, octree.leaf_info.size());
    EXPECT_EQ(std::uint64_t(stats.filled_leaves) + stats.empty_leaves, summary.leaves.size());
    EXPECT_NEAR(stats.replication_factor, double(stats.stored_splats) / double(stats.unique_splats), 1e-12);
    EXPECT_EQ(stats.depth, octree.info.depth);
    // borderline pairs (disk boundary within 1e-6 r of a leaf) must be rare
    EXPECT_LE(summary.borderline, summary.overlap_pairs / 1000 + 2);
    if (stats_out) *stats_out = stats;
    return summary;
}

TEST(SplatOctree, SphereReplicatedMatchesBruteForce) {
    const SplatSet s = sphere_with_knn_radii(1500, 1);
    OctreeParams params;  // X = 16
    OctreeStats stats;
    build_and_check(s, params, &stats);
    EXPECT_GT(stats.replication_factor, 1.5);  // k-NN disks overlap their neighbours' cells
    EXPECT_GE(stats.depth, 3u);
}

TEST(SplatOctree, SphereNotReplicatedHoldsEachSplatOnceInItsCentreLeaf) {
    const SplatSet s = sphere_with_knn_radii(1500, 2);
    OctreeParams params;
    params.replicate = false;
    OctreeStats stats;
    build_and_check(s, params, &stats);
    EXPECT_EQ(stats.stored_splats, 1500u);
    EXPECT_DOUBLE_EQ(stats.replication_factor, 1.0);
}

TEST(SplatOctree, SplitByCentresReplicatesIntoASmallerTree) {
    // thesis 3.2 / [LMR07]: subdivide on centres, then replicate into the leaves the disks overlap
    const SplatSet s = sphere_with_knn_radii(1500, 11);
    OctreeParams overlaps, centres;
    centres.split_by_centres = true;
    OctreeStats a, b;
    build_and_check(s, overlaps, &a);
    build_and_check(s, centres, &b);
    EXPECT_LT(b.nodes, a.nodes);
    EXPECT_LT(b.replication_factor, a.replication_factor);
    EXPECT_GT(b.max_leaf_count, 16u);  // leaves hold at most X centres, but more replicas
}

TEST(SplatOctree, LeafSizesFrom4To50) {
    const SplatSet s = sphere_with_knn_radii(600, 3);
    std::uint32_t previous_nodes = std::numeric_limits<std::uint32_t>::max();
    for (const std::uint32_t x : {4u, 10u, 16u, 50u}) {
        SCOPED_TRACE("X = " + std::to_string(x));
        OctreeParams params;
        params.max_leaf_splats = x;
        OctreeStats stats;
        build_and_check(s, params, &stats);
        EXPECT_LE(stats.nodes, previous_nodes);  // larger leaves, fewer nodes
        previous_nodes = stats.nodes;
    }
}

TEST(SplatOctree, RandomDisksWithAxisAlignedAndObliqueNormals) {
    std::mt19937_64 rng(4);
    std::uniform_real_distribution<double> u(-1, 1), logr(std::log(0.005), std::log(0.3));
    SplatSet s;
    for (int i = 0; i < 700; ++i) {
        s.positions.push_back({float(u(rng)), float(u(rng)), float(u(rng))});
        double n[3] = {u(rng), u(rng), u(rng)};
        if (i % 5 == 0) n[0] = n[1] = 0, n[2] = 1;  // disks parallel to cell faces
        if (i % 5 == 1) n[0] = 0;                   // parallel to the x axis
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) + 1e-300;
        s.normals.push_back({float(n[0] / len), float(n[1] / len), float(n[2] / len)});
        s.radii.push_back(float(std::exp(logr(rng))));
    }
    OctreeParams params;
    params.max_leaf_splats = 8;
    build_and_check(s, params);
}

TEST(SplatOctree, GridOfDisksInAxisPlanes) {
    // A regular grid on three axis-aligned planes: centres and disk edges fall on many common
    // coordinates, the exact test meets n_i = 0 on two axes.
    SplatSet s;
    for (int plane = 0; plane < 3; ++plane)
        for (int i = 0; i < 20; ++i)
            for (int j = 0; j < 20; ++j) {
                float p[3] = {0, 0, 0}, n[3] = {0, 0, 0};
                p[plane] = 0.25f * float(plane);
                p[(plane + 1) % 3] = float(i) / 19.0f;
                p[(plane + 2) % 3] = float(j) / 19.0f;
                n[plane] = 1;
                s.positions.push_back({p[0], p[1], p[2]});
                s.normals.push_back({n[0], n[1], n[2]});
                s.radii.push_back(1.5f / 19.0f);
            }
    OctreeParams params;
    params.max_leaf_splats = 6;
    build_and_check(s, params);
}

TEST(SplatOctree, DeepTreeReachesTwentyLevels) {
    // A tight cluster (spacing 1e-6) next to sparse points 1 apart: the cluster's cells shrink by 2^20+.
    SplatSet s;
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int i = 0; i < 30; ++i) {
        s.positions.push_back({float(u(rng)), float(u(rng)), float(u(rng))});
        s.normals.push_back({0, 0, 1});
        s.radii.push_back(0.05f);
    }
    for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j) {
            s.positions.push_back({0.3f + 1e-6f * float(i), 0.3f + 1e-6f * float(j), 0.3f});
            s.normals.push_back({0.6f, 0.0f, 0.8f});
            s.radii.push_back(1.2e-6f);
        }
    OctreeParams params;
    params.max_leaf_splats = 4;
    params.max_depth = 30;
    OctreeStats stats;
    build_and_check(s, params, &stats);
    EXPECT_GE(stats.depth, 20u);
}

TEST(SplatOctree, MaxDepthStopsSplitting) {
    // 40 disks through one point: no subdivision can separate them; the tree stops at max depth.
    SplatSet s;
    for (int i = 0; i < 40; ++i) {
        const double t = M_PI * i / 40;
        s.positions.push_back({float(0.1 * std::cos(t)), float(0.1 * std::sin(t)), 0.0f});
        s.normals.push_back({float(-std::sin(t)), float(std::cos(t)), 0.0f});
        s.radii.push_back(0.5f);
    }
    OctreeParams params;
    params.max_leaf_splats = 4;
    params.max_depth = 5;
    params.min_cell_ratio = 0;
    OctreeStats stats;
    build_and_check(s, params, &stats);
    EXPECT_EQ(stats.depth, 5u);
    EXPECT_GT(stats.max_leaf_count, 4u);
}

TEST(SplatOctree, MinCellRuleBoundsTheTreeWhereDisksOverlapMoreThanX) {
    // With X = 6 below the ~10-fold overlap of k = 9 disks, only the min-cell rule (or max depth)
    // stops the subdivision; it must keep the tree small and the result valid.
    const SplatSet s = sphere_with_knn_radii(300, 6);
    OctreeParams with_rule;
    with_rule.max_leaf_splats = 6;
    with_rule.max_depth = 8;
    OctreeParams without_rule = with_rule;
    without_rule.min_cell_ratio = 0;
    OctreeStats a, b;
    build_and_check(s, with_rule, &a);
    build_and_check(s, without_rule, &b);
    EXPECT_LT(a.nodes, b.nodes);
    EXPECT_EQ(b.depth, 8u);
}

TEST(SplatOctree, SkipsPointsWithoutAUsableRadius) {
    SplatSet s = sphere_with_knn_radii(500, 7);
    s.radii[3] = 0;
    s.radii[10] = -1;
    s.radii[20] = std::numeric_limits<float>::quiet_NaN();
    s.radii[30] = std::numeric_limits<float>::infinity();
    OctreeParams params;
    OctreeStats stats;
    build_and_check(s, params, &stats);
    EXPECT_EQ(stats.skipped_splats, 4u);
    EXPECT_EQ(stats.unique_splats, 496u);
}

TEST(SplatOctree, ThreadCountAndTaskSplitDoNotChangeTheResult) {
    SplatSet s = prt::test::sphere_points(80000, 8);
    std::mt19937_64 rng(8);
    std::uniform_real_distribution<double> jitter(0.8, 1.3);
    const double spacing = std::sqrt(4 * M_PI / 80000.0);
    for (std::size_t i = 0; i < s.positions.size(); ++i)
        s.radii.push_back(float(1.8 * spacing * jitter(rng)));
    OctreeParams one, three;
    one.threads = 1;
    three.threads = 3;
    one.max_leaf_splats = three.max_leaf_splats = 40;
    const auto a = build_octree(s.positions, s.normals, s.radii, one);
    const auto b = build_octree(s.positions, s.normals, s.radii, three);
    EXPECT_EQ(a.nodes, b.nodes);
    EXPECT_EQ(a.leaf_info, b.leaf_info);
    ASSERT_EQ(a.splats.size(), b.splats.size());
    for (std::size_t i = 0; i < a.splats.size(); ++i) ASSERT_EQ(a.splats[i].point, b.splats[i].point) << i;
    EXPECT_EQ(0, std::memcmp(&a.info, &b.info, sizeof a.info));
}

TEST(SplatOctree, InvalidInputIsAClearError) {
    SplatSet s = sphere_with_knn_radii(100, 9);
    OctreeParams params;
    auto zero = s.radii;
    std::fill(zero.begin(), zero.end(), 0.0f);
    EXPECT_THROW(build_octree(s.positions, s.normals, zero, params), prt::Error);
    std::vector<float> short_radii(s.radii.begin(), s.radii.begin() + 50);
    EXPECT_THROW(build_octree(s.positions, s.normals, short_radii, params), prt::Error);
    params.max_leaf_splats = 0;
    EXPECT_THROW(build_octree(s.positions, s.normals, s.radii, params), prt::Error);
    params.max_leaf_splats = 16;
    params.max_depth = 31;
    EXPECT_THROW(build_octree(s.positions, s.normals, s.radii, params), prt::Error);
}

TEST(SplatOctree, AddressRangeCheck) {
    using prt::pre::check_octree_limits;
    const std::uint64_t max_nodes = std::uint64_t(1) << 30;
    EXPECT_NO_THROW(check_octree_limits(max_nodes, max_nodes, 0xffffffffull));
    EXPECT_THROW(check_octree_limits(max_nodes + 1, 0, 0), prt::Error);
    EXPECT_THROW(check_octree_limits(0, max_nodes + 1, 0), prt::Error);
    EXPECT_THROW(check_octree_limits(0, 0, 0x100000000ull), prt::Error);
    try {
        check_octree_limits(max_nodes + 8, 0, 0);
    } catch (const prt::Error& e) {
        EXPECT_NE(std::string(e.what()).find("30-bit"), std::string::npos) << e.what();
    }
}

TEST(SplatOctree, RoundTripsThroughAPool) {
    // points -> pool -> octree over the pool's local-frame positions -> pool -> identical arrays
    const SplatSet s = sphere_with_knn_radii(800, 10);
    prt::pre::PointCloud cloud;
    for (std::size_t i = 0; i < s.positions.size(); ++i)
        cloud.positions.push_back(
            {100.0 + s.positions[i].x, -5.0 + s.positions[i].y, 1e3 + s.positions[i].z});
    cloud.normals = s.normals;
    cloud.radii = s.radii;
    prt::pool::PoolWriter first;
    prt::pre::write_point_sections(cloud, first);
    const prt::pool::PoolFile points = prt::pool::PoolFile::from_bytes(first.serialize(), "points");
    const auto pos = points.array<prt::pool::Float3>(prt::pool::SectionType::positions);
    const auto nrm = points.array<prt::pool::Float3>(prt::pool::SectionType::normals);
    const auto rad = points.array<float>(prt::pool::SectionType::radii);
    OctreeParams params;
    const prt::pre::SplatOctree octree = build_octree(pos, nrm, rad, params);
    const prt::pre::SplatOctree copy = octree;
    prt::pool::PoolWriter second;
    second.carry_over(points);
    prt::pre::add_octree_sections(octree, second);
    second.add_provenance("octree_build_test", "0", "{}");
    const prt::pool::PoolFile pool = prt::pool::PoolFile::from_bytes(second.serialize(), "octree");
    const auto info = pool.array<prt::pool::OctreeInfo>(prt::pool::SectionType::octree_info);
    ASSERT_EQ(info.size(), 1u);
    EXPECT_EQ(0, std::memcmp(&info[0], &copy.info, sizeof copy.info));
    const auto nodes = pool.array<std::uint32_t>(prt::pool::SectionType::octree_nodes);
    const auto leaves = pool.array<std::uint32_t>(prt::pool::SectionType::leaf_info);
    const auto splats = pool.array<prt::pool::Splat>(prt::pool::SectionType::splats);
    EXPECT_TRUE(std::equal(nodes.begin(), nodes.end(), copy.nodes.begin(), copy.nodes.end()));
    EXPECT_TRUE(std::equal(leaves.begin(), leaves.end(), copy.leaf_info.begin(), copy.leaf_info.end()));
    ASSERT_EQ(splats.size(), copy.splats.size());
    EXPECT_EQ(0, std::memcmp(splats.data(), copy.splats.data(), splats.size_bytes()));
    EXPECT_EQ(pool.array<float>(prt::pool::SectionType::radii).size(), 800u);  // carried over
    // and the stored octree is still correct against the pool's own positions
    prt::pre::SplatOctree reread{info[0],
                                 {nodes.begin(), nodes.end()},
                                 {leaves.begin(), leaves.end()},
                                 {splats.begin(), splats.end()}};
    prt::test::check_octree(reread, pos, nrm, rad, params);
}

}  // namespace

// The out-of-core brick build places a point from its centre where the cube c +- h reaches no
// mid-plane (bricks_from_points.cpp, place()): h must bound the prepared splat's box, rounded
// outward to float, on every axis, for any normal, at any scale, radii from tiny to huge.
TEST(SplatOctree, BoxBoundHoldsThePreparedSplatsBox) {
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    std::uniform_real_distribution<double> exponent(-30.0, 30.0);
    const float axis_normals[][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 0}};
    std::size_t tested = 0;
    for (int i = 0; i < 200000; ++i) {
        const double scale = std::exp2(exponent(rng));
        const prt::pool::Float3 p{float(unit(rng) * scale), float(unit(rng) * scale),
                                  float(unit(rng) * scale)};
        const float r = float(std::exp2(exponent(rng)) * (i % 3 == 0 ? scale : 1.0));
        prt::pool::Float3 n{unit(rng), unit(rng), unit(rng)};
        if (i % 5 == 0) {  // axis-aligned normals: the box is flat on that axis, widest on the others
            const float* a = axis_normals[i / 5 % 3];
            n = {a[0] * (i % 2 ? -1.0f : 1.0f), a[1], a[2]};
        }
        prt::pre::BuildSplat s;
        if (!prt::pre::prepare_build_splat(p, n, r, s)) continue;
        ++tested;
        const double c[3] = {p.x, p.y, p.z};
        for (int a = 0; a < 3; ++a) {
            const double h = prt::pre::build_splat_box_bound(c[a], r);
            ASSERT_GE(double(s.box_lo[a]), c[a] - h) << "point " << i << " axis " << a;
            ASSERT_LE(double(s.box_hi[a]), c[a] + h) << "point " << i << " axis " << a;
        }
    }
    EXPECT_GT(tested, 190000u);
}
