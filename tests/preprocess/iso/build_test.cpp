// The ISO octree's structure: leaf levels within the user's bounds (thesis 4.6, independent of the
// point count), 2:1 balance of filled leaves by brute force over all pairs (thesis 4.5.1), passive
// leaves (4.3.1), determinism across thread counts (the Morton codes: tests/preprocess/common).
#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <random>

#include "iso_morton.h"
#include "iso_test_util.h"

namespace {

using namespace prt;
using namespace prt::iso_test;

TEST(IsoBuild, FastExpMatchesStdExp) {
    double worst = 0;
    for (double x = -700.0; x <= 0.0; x += 0.0137) {
        const double e = std::exp(x);
        worst = std::max(worst, std::abs(iso::detail::exp_nonpositive(x) - e) / e);
    }
    EXPECT_LT(worst, 1e-14);
    EXPECT_EQ(iso::detail::exp_nonpositive(0.0), 1.0);
    EXPECT_GT(iso::detail::exp_nonpositive(-700.0), 0.0);
}

/// Whether two closed cells (level, x, y, z) share a point (face, edge or corner) without one
/// containing the other.
bool touch(const iso::LeafCell& a, const iso::LeafCell& b) {
    const std::uint32_t l = std::max(a.level, b.level);
    const std::uint32_t sa = l - a.level, sb = l - b.level;
    const std::int64_t alo[3] = {std::int64_t(a.x) << sa, std::int64_t(a.y) << sa, std::int64_t(a.z) << sa};
    const std::int64_t blo[3] = {std::int64_t(b.x) << sb, std::int64_t(b.y) << sb, std::int64_t(b.z) << sb};
    const std::int64_t ea = std::int64_t{1} << sa, eb = std::int64_t{1} << sb;
    for (int k = 0; k < 3; ++k)
        if (alo[k] > blo[k] + eb || blo[k] > alo[k] + ea) return false;
    return true;
}

TEST(IsoBuild, FilledLeavesAreTwoToOneBalanced) {
    // A noisy torus sampled unevenly: point density (hence leaf level) varies along the surface.
    PointSet s = synth_points(torus_shape(1.0, 0.35), 3000, 0.001);
    PointSet dense = synth_points(torus_shape(1.0, 0.35), 15000, 0.001);
    for (std::size_t i = 0; i < dense.positions.size(); ++i)
        if (dense.positions[i].x > 0.6f)
            s.positions.push_back(dense.positions[i]), s.normals.push_back(dense.normals[i]);
    for (const bool balance : {true, false}) {
        iso::BuildOptions o;
        o.max_level = 9;
        o.max_points = 1;
        o.balance = balance;
        o.drop_uncrossed = false;  // every filled leaf of the balanced tree
        o.threads = 2;
        const iso::IsoModel m = iso::build_iso(s.input(), o);
        const auto cells = iso::leaf_cells(m.nodes, m.info.leaf_count);
        std::size_t violations = 0;
        std::uint32_t lo = 99, hi = 0;
        for (const auto& c : cells) lo = std::min(lo, c.level), hi = std::max(hi, c.level);
        // Brute force over all pairs of leaves 2+ levels apart (only those can violate).
        std::vector<std::vector<std::size_t>> by_level(pool::k_max_iso_level + 1);
        for (std::size_t i = 0; i < cells.size(); ++i) by_level[cells[i].level].push_back(i);
        for (std::size_t i = 0; i < cells.size(); ++i)
            for (std::uint32_t l = cells[i].level + 2; l <= pool::k_max_iso_level; ++l)
                for (const std::size_t j : by_level[l]) violations += touch(cells[i], cells[j]);
        std::printf(
            "balance %d: %zu leaves, levels %u..%u, %llu balance splits, %zu pairs 2+ levels apart "
            "touching\n",
            balance, cells.size(), lo, hi, static_cast<unsigned long long>(m.stats.balance_splits),
            violations);
        if (balance) {
            EXPECT_EQ(violations, 0u);
            EXPECT_GT(m.stats.balance_splits, 0u);
            EXPECT_TRUE(m.info.flags & pool::k_iso_balanced);
        } else {
            EXPECT_GT(violations, 0u);  // the test model needs balancing at all
        }
        EXPECT_GT(hi, lo + 1);
    }
}

/// Level-`level` cells of the ISO's root grid whose corners lie on both sides of the unit sphere.
std::size_t sphere_cells(const pool::IsoInfo& info, int level) {
    const double e = std::ldexp(double(info.root_size), -level);
    const int n = 1 << level;
    std::size_t crossed = 0;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                bool pos = false, neg = false;
                for (int c = 0; c < 8; ++c) {
                    const D3 q{info.root_min[0] + e * (x + (c & 1)),
                               info.root_min[1] + e * (y + ((c >> 1) & 1)),
                               info.root_min[2] + e * (z + ((c >> 2) & 1))};
                    (norm3(q) > 1 ? pos : neg) = true;
                }
                crossed += pos && neg;
            }
    return crossed;
}

TEST(IsoBuild, LevelsStayWithinBoundsIndependentOfPointCount) {
    // thesis 4.6: with min = max = L the leaves are the level-L cells the surface crosses, however
    // many points sample it. (eq. 4.3's surface lies about sigma^2 / R inside the sphere, sigma
    // shrinking with more points, so cells the sphere barely clips come and go: a few percent.)
    for (const std::uint64_t n : {20000u, 80000u}) {
        const PointSet s = synth_points(sphere_shape(1.0), n);
        iso::BuildOptions o;
        o.min_level = 6;
        o.max_level = 6;
        o.threads = 2;
        const iso::IsoModel m = iso::build_iso(s.input(), o);
        const auto cells = iso::leaf_cells(m.nodes, m.info.leaf_count);
        for (const auto& c : cells) {
            EXPECT_EQ(c.level, 6u);
        }
        const std::size_t analytic = sphere_cells(m.info, 6);
        std::printf(
            "level 6 sphere from %llu points: %zu leaves, %zu cells cross the true sphere (%llu active, "
            "%llu passive, %llu without a sign change)\n",
            static_cast<unsigned long long>(n), cells.size(), analytic,
            static_cast<unsigned long long>(m.stats.active_leaves),
            static_cast<unsigned long long>(m.stats.passive_leaves),
            static_cast<unsigned long long>(m.stats.uncrossed_leaves));
        EXPECT_GT(double(cells.size()), 0.93 * double(analytic));
        EXPECT_LT(double(cells.size()), 1.01 * double(analytic));
    }
    // Adaptive: min and max bound every leaf.
    const PointSet s = synth_points(sphere_shape(1.0), 30000);
    iso::BuildOptions o;
    o.min_level = 4;
    o.max_level = 7;
    o.threads = 2;
    const iso::IsoModel m = iso::build_iso(s.input(), o);
    for (const auto& c : iso::leaf_cells(m.nodes, m.info.leaf_count)) {
        EXPECT_GE(c.level, 4u);
        EXPECT_LE(c.level, 7u);
    }
}

TEST(IsoBuild, PassiveLeavesAndClosureCloseTheSurface) {
    // Without passive leaves (thesis 4.3.1) and without the surface closure, points of the true
    // surface fall in empty leaves between the point-holding ones; either fills them.
    const PointSet s = synth_points(sphere_shape(1.0), 20000);
    std::size_t missing[3] = {0, 0, 0};
    for (int config = 0; config < 3; ++config) {
        iso::BuildOptions o;
        o.max_level = 9;
        o.max_points = 1;
        o.passive = config != 0 && config != 2;
        o.closure = config != 0;
        o.drop_uncrossed = false;  // every filled leaf, also those the (slightly shrunk) f = 0 misses
        o.threads = 2;
        const iso::IsoModel m = iso::build_iso(s.input(), o);
        const core::IsoView v = iso::make_view(m);
        if (o.passive) {
            EXPECT_GT(m.stats.passive_leaves, 0u);
        } else {
            EXPECT_EQ(m.stats.passive_leaves, 0u);
        }
        if (!o.closure) {
            EXPECT_EQ(m.stats.closure_leaves, 0u);
        }
        std::mt19937 rng(1);
        std::normal_distribution<double> g;
        for (int i = 0; i < 20000; ++i) {
            D3 p{g(rng), g(rng), g(rng)};
            const double l = norm3(p);
            for (double& c : p) c /= l;
            float f;
            std::uint32_t level;
            if (!core::iso_value_at(v, vf(p), f, level)) ++missing[config];
        }
        std::printf(
            "passive %d, closure %d: %llu passive + %llu closure leaves; %zu of 20000 surface samples in "
            "no filled leaf\n",
            o.passive, o.closure, static_cast<unsigned long long>(m.stats.passive_leaves),
            static_cast<unsigned long long>(m.stats.closure_leaves), missing[config]);
    }
    EXPECT_GT(missing[0], 100u);
    EXPECT_EQ(missing[1], 0u);
    EXPECT_LT(missing[2], 100u);  // closure alone grows from crossed leaves: misses clipped corners
}

// The 2:1 balance and the surface closure run their read-only parts in parallel and their
// splits in the serial order: the same tree for any thread count, also where both have work
// (the noisier torus).
TEST(IsoBuild, DeterministicAcrossThreadCounts) {
    for (const double noise : {0.001, 0.02}) {
        SCOPED_TRACE(noise);
        const PointSet s = synth_points(torus_shape(1.0, 0.4), 20000, noise, true);
        iso::BuildOptions o;
        o.storage = iso::Storage::both;
        o.threads = 1;
        const iso::IsoModel a = iso::build_iso(s.input(), o);
        EXPECT_GT(a.stats.balance_splits, 0u);
        if (noise > 0.01) {
            EXPECT_GT(a.stats.closure_leaves, 0u);
        }
        o.threads = 3;
        const iso::IsoModel b = iso::build_iso(s.input(), o);
        EXPECT_EQ(a.stats.balance_splits, b.stats.balance_splits);
        EXPECT_EQ(a.stats.closure_leaves, b.stats.closure_leaves);
        ASSERT_EQ(a.nodes, b.nodes);
        ASSERT_EQ(a.leaves_q8.size(), b.leaves_q8.size());
        EXPECT_EQ(0, std::memcmp(a.leaves_q8.data(), b.leaves_q8.data(),
                                 a.leaves_q8.size() * sizeof(pool::IsoLeafQ8)));
        EXPECT_EQ(0, std::memcmp(a.leaves_f32.data(), b.leaves_f32.data(),
                                 a.leaves_f32.size() * sizeof(pool::IsoLeafF32)));
        EXPECT_EQ(0, std::memcmp(&a.info, &b.info, sizeof(pool::IsoInfo)));
    }
}

// The surface closure's parallel pass closes the faces its serial pass would pass without a change
// (same-level filled leaves, empty cells no support reaches, finer leaves whose empty ones on the
// face keep one sign): sending every crossed face through the serial pass builds the same tree.
// Noisy models, where the closure adds leaves through each kind of face (the random torus: also
// empty leaves beyond finer ones, which a parallel pass closing every such face would miss).
TEST(IsoBuild, ClosureParallelPassDecidesAsTheSerialPass) {
    struct Case {
        const char* name;
        PointSet points;
        std::uint32_t max_level;
    };
    const Case cases[] = {
        {"torus, noise 0.02", synth_points(torus_shape(1.0, 0.4), 20000, 0.02, true), 10},
        {"torus, random, noise 0.01",
         synth_points(torus_shape(1.0, 0.25), 40000, 0.01, false, synth::Sampling::random), 8},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        iso::BuildOptions o;
        o.storage = iso::Storage::both;
        o.max_level = c.max_level;
        o.threads = 3;
        const iso::IsoModel a = iso::build_iso(c.points.input(), o);
        ASSERT_GT(a.stats.closure_leaves, 0u);
        o.closure_serial_only = true;
        const iso::IsoModel b = iso::build_iso(c.points.input(), o);
        EXPECT_EQ(a.stats.closure_leaves, b.stats.closure_leaves);
        ASSERT_EQ(a.nodes, b.nodes);
        ASSERT_EQ(a.leaves_f32.size(), b.leaves_f32.size());
        EXPECT_EQ(0, std::memcmp(a.leaves_f32.data(), b.leaves_f32.data(),
                                 a.leaves_f32.size() * sizeof(pool::IsoLeafF32)));
    }
}

}  // namespace
