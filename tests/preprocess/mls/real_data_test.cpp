// The MLS surface of a real point set: the CGAL kitten (5,210 points with unit normals, from
// ../shared/data; skipped where absent). Radii are the 10th-nearest-neighbour distances computed
// here by brute force (what prt-radii's k = 9 gives, without FLANN). Checks the tree invariants
// and roots against the brute-force double-precision F on the real, unevenly sampled data.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "mls_test_util.h"
#include "mls_trace.h"

namespace {

using namespace prt;
using namespace prt::mls_test;

PointSet read_kitten(const std::filesystem::path& file) {
    PointSet s;
    std::ifstream in(file);
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream ls(line);
        float v[6];
        if (!(ls >> v[0] >> v[1] >> v[2] >> v[3] >> v[4] >> v[5])) continue;
        s.positions.push_back({v[0], v[1], v[2]});
        s.normals.push_back({v[3], v[4], v[5]});
    }
    const std::size_t n = s.positions.size();
    s.radii.resize(n);
    std::vector<double> d(n);
    for (std::size_t i = 0; i < n; ++i) {
        const D3 p = d3(s.positions[i]);
        for (std::size_t j = 0; j < n; ++j) {
            const D3 q = d3(s.positions[j]);
            d[j] =
                (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
        }
        std::nth_element(d.begin(), d.begin() + 9, d.end());  // d[0] = 0 is the point itself
        s.radii[i] = float(std::sqrt(d[9]));
    }
    return s;
}

TEST(MlsRealData, KittenTreeInvariantsAndRoots) {
    const std::filesystem::path file =
        std::filesystem::path(PRT_SHARED_DATA_DIR) / "points/cgal_kitten/kitten.xyz";
    if (!std::filesystem::exists(file))
        GTEST_SKIP() << "real data not found: " << file << " (../shared/data is absent)";
    const PointSet s = read_kitten(file);
    ASSERT_EQ(s.positions.size(), 5210u);
    const mls::MlsModel m = build(s);
    EXPECT_EQ(m.stats.skipped, 0u);
    // Every filled leaf references every splat whose support reaches it.
    for (const LeafCell& leaf : leaf_cells(m)) {
        if (leaf.count == 0) continue;
        std::set<std::uint32_t> refs(m.refs.begin() + leaf.first, m.refs.begin() + leaf.first + leaf.count);
        for (std::uint32_t i = 0; i < m.splats.size(); ++i) {
            const double inv = m.splats[i].inv_support;
            if (box_distance2(d3(m.splats[i].position), leaf.cell) * inv * inv < 1.0) {
                ASSERT_TRUE(refs.count(i)) << "leaf " << leaf.node << " misses splat " << i;
            }
        }
    }
    // Roots of rays through the model against the brute-force F.
    const core::MlsView view = mls::make_view(m);
    D3 lo{1e9, 1e9, 1e9}, hi{-1e9, -1e9, -1e9};
    for (const pool::Float3& p : s.positions)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], double((&p.x)[a]));
            hi[a] = std::max(hi[a], double((&p.x)[a]));
        }
    const D3 c{(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2};
    const double size = norm3(D3{hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(-0.3, 0.3);
    std::vector<core::Ray> rays;
    for (int i = 0; i < 60; ++i) {
        const core::Vec3 o{float(c[0] + size * u(rng)), float(c[1] + size * u(rng)),
                           float(c[2] + 2.0 * size)};
        const core::Vec3 t{float(c[0] + size * u(rng)), float(c[1] + size * u(rng)), float(c[2])};
        rays.push_back({o, core::normalize(t - o), core::k_inf, 0u});
    }
    const mls::TraceResult ref =
        mls::trace_rays(view, rays, mls::reference_params(), 2, mls::k_reference_precision);
    int hits = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const double t_bf = brute_root(m.splats, d3(rays[i].origin), d3(rays[i].dir), 0.0, 4.0 * size, 3000);
        if (t_bf < 0) {
            EXPECT_FALSE(ref.found[i]) << "ray " << i;
            continue;
        }
        ++hits;
        ASSERT_TRUE(ref.found[i]) << "ray " << i << " misses a root at t = " << t_bf;
        EXPECT_NEAR(ref.hits[i].t, t_bf, 1e-5 * size) << "ray " << i;
    }
    EXPECT_GT(hits, 20);
}

}  // namespace
