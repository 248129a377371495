// The kd-tree invariants (WS05 3.4): every leaf references every splat whose support reaches its
// cell; shrinking (3.4.1) keeps every zero of F (found by dense brute-force sampling); interval
// classification is conservative; encouraged splits (3.4.2) and post-collapse (3.4.3) do what
// they say; bad inputs give errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "mls_test_util.h"
#include "prt/error.h"
#include "synth.h"

namespace {

using namespace prt;
using namespace prt::mls_test;

/// A sphere with noise along the normal (bumpy: many small features for the shrinking to keep).
PointSet noisy_sphere(std::uint64_t n, double noise, std::uint64_t seed) {
    synth::SynthOptions o;
    o.shape.kind = synth::ShapeKind::sphere;
    o.count = n;
    o.noise = noise;
    o.seed = seed;
    o.sampling = synth::Sampling::random;
    o.threads = 2;
    const synth::SynthResult r = synth::synthesize(o);
    PointSet s;
    const double density = double(n) / (4.0 * M_PI);
    for (std::size_t i = 0; i < r.cloud.size(); ++i) {
        const auto& p = r.cloud.positions[i];
        s.positions.push_back({float(p[0]), float(p[1]), float(p[2])});
        s.normals.push_back(r.cloud.normals[i]);
        s.radii.push_back(float(std::sqrt(12.0 / (M_PI * density))));
    }
    return s;
}

TEST(MlsBuild, EveryLeafReferencesEverySplatWhoseSupportReachesIt) {
    const PointSet s = noisy_sphere(3000, 0.002, 5);
    for (const bool shrink : {false, true}) {
        mls::BuildOptions opt;
        opt.shrink = shrink;
        const mls::MlsModel m = build(s, opt);
        std::size_t nonempty = 0;
        for (const LeafCell& leaf : leaf_cells(m)) {
            std::set<std::uint32_t> refs(m.refs.begin() + leaf.first,
                                         m.refs.begin() + leaf.first + leaf.count);
            EXPECT_EQ(refs.size(), leaf.count) << "a splat referenced twice by one leaf";
            std::size_t reaching = 0;
            for (std::uint32_t i = 0; i < m.splats.size(); ++i) {
                const double inv = m.splats[i].inv_support;
                const bool reaches = box_distance2(d3(m.splats[i].position), leaf.cell) * inv * inv < 1.0;
                reaching += reaches;
                if (leaf.count > 0 && reaches) {
                    ASSERT_TRUE(refs.count(i)) << "leaf " << leaf.node << " misses splat " << i;
                }
            }
            // Without shrinking an empty leaf is one no support reaches; with it, it may also be
            // a cell proven free of the surface (checked by the next test).
            if (!shrink && leaf.count == 0) {
                EXPECT_EQ(reaching, 0u) << "leaf " << leaf.node;
            }
            nonempty += leaf.count > 0;
        }
        EXPECT_GT(nonempty, 10u);
    }
}

/// Zeros of the brute-force F (sign changes with W > 0 along many random lines, bisected in
/// double) must lie in non-empty leaves of the shrunk tree.
TEST(MlsBuild, ShrunkCellsStillContainEveryZeroOfF) {
    const PointSet s = noisy_sphere(2500, 0.004, 11);
    mls::BuildOptions opt;
    opt.shrink = true;
    opt.shrink_slices = 12;
    const mls::MlsModel m = build(s, opt);
    ASSERT_GT(m.stats.culled_leaves + m.stats.shrunk_leaves, 0u)
        << "nothing was shrunk: the test proves nothing";
    const std::vector<LeafCell> leaves = leaf_cells(m);
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> u(-1.2, 1.2);
    std::size_t zeros = 0;
    for (int line = 0; line < 60; ++line) {
        const D3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)};
        const D3 d{b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        const int samples = 3000;
        BruteF prev = brute_f(m.splats, a);
        double prev_t = 0;
        for (int i = 1; i <= samples; ++i) {
            const double t = double(i) / samples;
            const D3 x{a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2]};
            const BruteF cur = brute_f(m.splats, x);
            if (prev.w > 0 && cur.w > 0 && (prev.f > 0) != (cur.f > 0)) {
                double lo = prev_t, hi = t, flo = prev.f;
                for (int k = 0; k < 60; ++k) {
                    const double mid = 0.5 * (lo + hi);
                    const BruteF fm =
                        brute_f(m.splats, D3{a[0] + mid * d[0], a[1] + mid * d[1], a[2] + mid * d[2]});
                    if ((fm.f > 0) == (flo > 0)) {
                        lo = mid;
                        flo = fm.f;
                    } else {
                        hi = mid;
                    }
                }
                const double tz = 0.5 * (lo + hi);
                const D3 z{a[0] + tz * d[0], a[1] + tz * d[1], a[2] + tz * d[2]};
                bool in_filled = false;
                for (const LeafCell& leaf : leaves)
                    if (leaf.count > 0 && box_distance2(z, leaf.cell) <= 1e-24) in_filled = true;
                EXPECT_TRUE(in_filled) << "a zero of F at " << z[0] << "," << z[1] << "," << z[2]
                                       << " lies in no non-empty leaf";
                ++zeros;
            }
            prev = cur;
            prev_t = t;
        }
    }
    EXPECT_GT(zeros, 40u);
}

/// may_contain_surface is conservative: boxes it calls free hold no sign change of the
/// brute-force F with W > 0 on a dense grid.
TEST(MlsBuild, IntervalClassificationIsConservative) {
    const PointSet s = noisy_sphere(1500, 0.003, 3);
    const mls::MlsModel m = build(s, mls::BuildOptions{});
    std::vector<std::uint32_t> all(m.splats.size());
    for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> c(-1.1, 1.1), e(0.01, 0.12);
    int free_boxes = 0, maybe_boxes = 0;
    for (int trial = 0; trial < 150; ++trial) {
        mls::Box b;
        for (int a = 0; a < 3; ++a) {
            const double mid = c(rng), half = e(rng);
            b.lo[a] = mid - half;
            b.hi[a] = mid + half;
        }
        const bool maybe = mls::may_contain_surface(b, m.splats, all, 6);
        maybe_boxes += maybe;
        if (maybe) continue;
        ++free_boxes;
        const int g = 9;
        int pos = 0, neg = 0;
        for (int i = 0; i < g; ++i)
            for (int j = 0; j < g; ++j)
                for (int k = 0; k < g; ++k) {
                    const D3 x{b.lo[0] + (b.hi[0] - b.lo[0]) * i / (g - 1),
                               b.lo[1] + (b.hi[1] - b.lo[1]) * j / (g - 1),
                               b.lo[2] + (b.hi[2] - b.lo[2]) * k / (g - 1)};
                    const BruteF f = brute_f(m.splats, x);
                    if (f.w > 0) (f.f > 0 ? pos : neg)++;
                }
        EXPECT_TRUE(pos == 0 || neg == 0) << "box " << trial << " called free holds both signs of F";
    }
    EXPECT_GT(free_boxes, 30);
    EXPECT_GT(maybe_boxes, 10);
}

TEST(MlsBuild, OptimizationsDoWhatTheySay) {
    const PointSet s = fibonacci_sphere(4000);
    mls::BuildOptions none;
    none.shrink = none.encourage = none.collapse = false;
    mls::BuildOptions shrink = none;
    shrink.shrink = true;
    mls::BuildOptions collapse = shrink;
    collapse.collapse = true;
    mls::BuildOptions encourage = none;
    encourage.encourage = true;
    const mls::MlsModel m_none = build(s, none), m_shrink = build(s, shrink), m_collapse = build(s, collapse),
                        m_enc = build(s, encourage);
    // 3.4.1: shrinking empties or shrinks leaves, cuts the filled volume and drops refs.
    EXPECT_GT(m_shrink.stats.shrunk_leaves + m_shrink.stats.culled_leaves, 0u);
    EXPECT_LT(m_shrink.stats.volume_after, 0.8 * m_shrink.stats.volume_before);
    EXPECT_LT(m_shrink.refs.size(), m_none.refs.size());
    EXPECT_EQ(m_none.stats.shrink_splits, 0u);
    // 3.4.3: post-collapse removes splits with two empty children, and nothing else.
    EXPECT_GT(m_collapse.stats.collapsed, 0u);
    EXPECT_EQ(m_collapse.nodes.size(), m_shrink.nodes.size() - 2 * m_collapse.stats.collapsed);
    EXPECT_EQ(m_collapse.refs.size(), m_shrink.refs.size());
    for (const LeafCell& l : leaf_cells(m_collapse)) (void)l;  // still a proper tree
    // 3.4.2: E(n) < 1 lowers the cost of small cells: the SAH splits further.
    EXPECT_GT(m_enc.stats.sah_leaves, m_none.stats.sah_leaves);
    EXPECT_DOUBLE_EQ(mls::encourage_factor(1), 0.5);
    EXPECT_DOUBLE_EQ(mls::encourage_factor(21), 1.0);
    EXPECT_DOUBLE_EQ(mls::encourage_factor(100), 1.0);
    EXPECT_DOUBLE_EQ(mls::encourage_factor(40, 40.0), 1.0);
    // Flags record the optimizations.
    EXPECT_EQ(m_none.info.flags, 0u);
    EXPECT_EQ(m_collapse.info.flags, pool::k_mls_shrunk | pool::k_mls_collapsed);
}

TEST(MlsBuild, SameTreeForAnyThreadCount) {
    const PointSet s = fibonacci_sphere(3000);
    mls::BuildOptions one, four;
    one.threads = 1;
    four.threads = 4;
    const mls::MlsModel a = build(s, one), b = build(s, four);
    ASSERT_EQ(a.nodes.size(), b.nodes.size());
    ASSERT_EQ(a.refs, b.refs);
    for (std::size_t i = 0; i < a.nodes.size(); ++i) {
        EXPECT_EQ(a.nodes[i].payload, b.nodes[i].payload);
        EXPECT_EQ(a.nodes[i].meta, b.nodes[i].meta);
    }
}

TEST(MlsBuild, SkipsUnusablePointsAndRejectsBadInput) {
    PointSet s = fibonacci_sphere(200);
    s.radii[3] = 0.0f;
    s.radii[4] = std::numeric_limits<float>::quiet_NaN();
    s.normals[5] = {0, 0, 0};
    s.positions[6].x = std::numeric_limits<float>::infinity();
    const mls::MlsModel m = build(s);
    EXPECT_EQ(m.stats.skipped, 4u);
    EXPECT_EQ(m.splats.size(), 196u);
    for (const pool::MlsSplat& sp : m.splats) EXPECT_TRUE(sp.point < 3 || sp.point > 6);

    PointSet bad = s;
    bad.radii.pop_back();
    EXPECT_THROW(build(bad), Error);
    PointSet none = fibonacci_sphere(10);
    for (float& r : none.radii) r = 0.0f;
    try {
        build(none);
        FAIL() << "no usable splat must throw";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("radius"), std::string::npos) << e.what();
    }
    mls::BuildOptions opt;
    opt.support_factor = -1.0f;
    EXPECT_THROW(build(s, opt), Error);
    opt = {};
    opt.max_depth = 60;
    EXPECT_THROW(build(s, opt), Error);
    opt = {};
    opt.shrink_axes = 2;
    EXPECT_THROW(build(s, opt), Error);
}

}  // namespace
