// Octree traversal (thesis 2.2.1-2.2.2, DESIGN.md numerical robustness): the walk of core/octree.h
// against a double-precision reference over the test builder's leaves, at extreme scales and
// offsets, for rays grazing faces, edges and corners, and for trees 20+ levels deep.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "prt/core/octree.h"
#include "ray_reference.h"
#include "test_scene.h"

namespace prt::test {
namespace {

struct Walked {
    std::vector<core::OctreeLeaf> leaves;
    bool truncated = false;
    bool began = false;
};

Walked walk(const core::OctreeView& v, core::Vec3 o, core::Vec3 d, float t_max = core::k_inf,
            std::uint32_t max_steps = 1u << 24) {
    Walked w;
    core::OctreeWalk state;
    w.began = core::walk_begin(v, o, d, 0.0f, t_max, max_steps, state);
    if (!w.began) return w;
    core::OctreeLeaf leaf;
    while (core::walk_next(v, state, leaf)) w.leaves.push_back(leaf);
    w.truncated = state.truncated;
    return w;
}

/// Double-precision slab test of the ray O + t D against [lo, hi]^3, t in [t_lo, t_hi].
bool slab(const D3& O, const D3& D, const double lo[3], const double hi[3], double t_lo, double t_hi,
          double& ta, double& tb) {
    ta = t_lo;
    tb = t_hi;
    return prt::bench::clip_to_box(O, D, lo, hi, ta, tb);
}

/// Checks a walk against the reference; returns the number of visited leaves.
std::size_t check_walk(const TestOctree& tree, core::Vec3 o, core::Vec3 d, const std::string& what) {
    SCOPED_TRACE(what);
    const core::OctreeView v = tree.view();
    const Walked w = walk(v, o, d);
    EXPECT_FALSE(w.truncated);
    // The ray in normalized root coordinates, in double from the same float inputs.
    const double size = tree.info.root_size;
    const D3 O{(double(o.x) - tree.info.root_min[0]) / size, (double(o.y) - tree.info.root_min[1]) / size,
               (double(o.z) - tree.info.root_min[2]) / size};
    const D3 D{double(d.x) / size, double(d.y) / size, double(d.z) / size};
    const double unit[3] = {0, 0, 0}, one[3] = {1, 1, 1};
    double root_in, root_out;
    const bool hits_root = slab(O, D, unit, one, 0.0, 1e300, root_in, root_out);
    // Tolerance in normalized units: float rounding of positions of magnitude |O|, |O + D t|.
    double mag = 1.0;
    for (int a = 0; a < 3; ++a)
        mag = std::max({mag, std::abs(O[a]), hits_root ? std::abs(O[a] + D[a] * root_out) : 0.0});
    const double eps = 1e-6 * mag;  // a few float ulps of the coordinates (t carries several roundings)
    if (!hits_root || root_out - root_in < 1e-12) {
        // A miss (or a touch): the walk may not start, or must stay tiny.
        for (const auto& l : w.leaves) EXPECT_LE((l.t1 - l.t0) * d3_len(D), 2 * eps);
        return w.leaves.size();
    }
    EXPECT_TRUE(w.began);
    if (w.leaves.empty()) {
        ADD_FAILURE() << "the walk visited no leaf";
        return 0;
    }
    // Contiguous and front to back; starts at the root entry, ends at its exit.
    const double dl = d3_len(D);
    EXPECT_NEAR(w.leaves.front().t0 * dl, root_in * dl, eps);
    EXPECT_NEAR(w.leaves.back().t1 * dl, root_out * dl, 2 * eps);
    for (std::size_t i = 0; i + 1 < w.leaves.size(); ++i) {
        EXPECT_EQ(w.leaves[i].t1, w.leaves[i + 1].t0) << "leaf " << i;
        EXPECT_LE(w.leaves[i].t0, w.leaves[i].t1) << "leaf " << i;
    }
    // Every visited leaf is a leaf of the tree (same node word at that level and cell) and lies on
    // the ray: its box, grown by eps, meets the segment [t0, t1].
    std::map<std::tuple<std::uint32_t, std::uint64_t, std::uint64_t, std::uint64_t>, const TestLeaf*> by_cell;
    for (const TestLeaf& l : tree.leaves) by_cell[{l.level, l.cell[0], l.cell[1], l.cell[2]}] = &l;
    std::set<const TestLeaf*> visited;
    for (std::size_t i = 0; i < w.leaves.size(); ++i) {
        const core::OctreeLeaf& l = w.leaves[i];
        auto it = by_cell.find({l.level, l.cell.x, l.cell.y, l.cell.z});
        if (it == by_cell.end()) {
            ADD_FAILURE() << "leaf " << i << " (level " << l.level << ") is not a leaf of the tree";
            continue;
        }
        EXPECT_EQ(l.node, tree.nodes[it->second->node_index]) << "leaf " << i;
        visited.insert(it->second);
        const double s = 1.0 / double(1ull << l.level);
        const double lo[3] = {l.cell.x * s - eps, l.cell.y * s - eps, l.cell.z * s - eps};
        const double hi[3] = {(l.cell.x + 1) * s + eps, (l.cell.y + 1) * s + eps, (l.cell.z + 1) * s + eps};
        double ta, tb;
        const double slack = eps / std::max(dl, 1e-300);
        EXPECT_TRUE(slab(O, D, lo, hi, l.t0 - slack, l.t1 + slack, ta, tb))
            << "leaf " << i << " at level " << l.level << " is off the ray";
    }
    // Every leaf the ray clearly crosses (its box shrunk by eps still meets the ray) was visited.
    for (const TestLeaf& l : tree.leaves) {
        const double s = 1.0 / double(1ull << l.level);
        if (s <= 4 * eps) continue;
        const double lo[3] = {l.cell[0] * s + eps, l.cell[1] * s + eps, l.cell[2] * s + eps};
        const double hi[3] = {(l.cell[0] + 1) * s - eps, (l.cell[1] + 1) * s - eps,
                              (l.cell[2] + 1) * s - eps};
        double ta, tb;
        if (slab(O, D, lo, hi, 0.0, 1e300, ta, tb) && (tb - ta) * dl > eps) {
            EXPECT_TRUE(visited.count(&l))
                << "leaf at level " << l.level << " cell (" << l.cell[0] << "," << l.cell[1] << ","
                << l.cell[2] << ") crossed by the ray but not visited";
        }
    }
    return w.leaves.size();
}

/// Splats (tiny, radius ~0) at the given local points: the tree structure is what matters here.
std::vector<pool::Splat> point_splats(const std::vector<D3>& pts, float radius) {
    std::vector<pool::Splat> s;
    for (std::uint32_t i = 0; i < pts.size(); ++i) {
        s.push_back(
            pool::Splat{{float(pts[i][0]), float(pts[i][1]), float(pts[i][2])}, radius, {0, 0, 1}, i});
    }
    return s;
}

TestOctree random_tree(double scale, const D3& root_min, std::uint32_t seed, std::size_t n = 400) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<D3> pts;
    for (std::size_t i = 0; i < n; ++i) {
        // Half uniform, half clustered, so leaves appear at many levels.
        const double cx = i % 2 ? u(rng) : 0.3 + 0.05 * u(rng);
        pts.push_back({root_min[0] + scale * cx, root_min[1] + scale * u(rng),
                       root_min[2] + scale * (i % 2 ? u(rng) : 0.6 + 0.03 * u(rng))});
    }
    return build_test_octree(point_splats(pts, static_cast<float>(scale * 1e-4)), root_min, scale, 2, 12);
}

core::Vec3 fv(const D3& a) {
    return {float(a[0]), float(a[1]), float(a[2])};
}

void random_rays(const TestOctree& tree, std::uint32_t seed, int count, const std::string& label) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 2.0), in(0.0, 1.0);
    const double s = tree.info.root_size;
    const D3 rm{tree.info.root_min[0], tree.info.root_min[1], tree.info.root_min[2]};
    std::size_t total = 0;
    for (int i = 0; i < count; ++i) {
        // From anywhere around (or inside) the root towards a point inside it.
        const D3 o = d3_add(rm, d3_mul({u(rng), u(rng), u(rng)}, s));
        const D3 target = d3_add(rm, d3_mul({in(rng), in(rng), in(rng)}, s));
        D3 d = d3_sub(target, o);
        if (d3_len(d) < 1e-3 * s) continue;
        d = d3_norm(d);
        total += check_walk(tree, fv(o), fv(d), label + " ray " + std::to_string(i));
    }
    // The rays did cross the tree: on average several leaves per ray.
    EXPECT_GT(total, static_cast<std::size_t>(count))
        << "depth " << tree.info.depth << ", " << tree.leaves.size() << " leaves";
}

TEST(OctreeWalk, RandomRaysUnitScale) {
    random_rays(random_tree(1.0, {0, 0, 0}, 1), 11, 300, "unit");
}

TEST(OctreeWalk, RandomRaysTinyModel) {
    // A model 1e-4 units across: no world-space epsilon may swamp it.
    random_rays(random_tree(1e-4, {-5e-5, 2e-5, 0}, 2), 12, 300, "1e-4");
}

TEST(OctreeWalk, RandomRaysHugeModel) {
    random_rays(random_tree(1e6, {-5e5, -3e5, 2e5}, 3), 13, 300, "1e6");
}

TEST(OctreeWalk, RandomRaysFarFromOrigin) {
    // A 1e6-unit model whose root corner is 1e6 from the origin (local frame far off, worst case
    // for float: the runtime avoids it with ModelInfo::origin, but the walk must stay exact).
    random_rays(random_tree(1e6, {1e6, -1e6, 1e6}, 4), 14, 200, "1e6 at 1e6");
}

TEST(OctreeWalk, GrazingFacesEdgesCorners) {
    // A complete tree of depth 4 (every cell split): every plane k/16 is a cell face.
    std::vector<D3> pts;
    for (int i = 0; i < 16; ++i)
        for (int j = 0; j < 16; ++j)
            for (int k = 0; k < 16; ++k) pts.push_back({(i + 0.5) / 16, (j + 0.5) / 16, (k + 0.5) / 16});
    const TestOctree tree = build_test_octree(point_splats(pts, 1e-6f), {0, 0, 0}, 1.0, 1, 4);
    ASSERT_EQ(tree.info.depth, 4u);
    int n = 0;
    // Along faces (one coordinate on a cell face), along edges (two), through corners (diagonals).
    for (int f = 0; f <= 16; ++f) {
        const float c = f / 16.0f;
        n += check_walk(tree, {-0.5f, c, 0.3f}, {1, 0, 0}, "face x " + std::to_string(f)) > 0;
        n += check_walk(tree, {0.3f, 1.5f, c}, {0, -1, 0}, "face y " + std::to_string(f)) > 0;
        n += check_walk(tree, {c, c, -2.0f}, {0, 0, 1}, "edge z " + std::to_string(f)) > 0;
        n += check_walk(tree, {c, 1.0f - c, 3.0f}, {0, 0, -1}, "edge -z " + std::to_string(f)) > 0;
        n += check_walk(tree, {c - 1, -1.0f, 0.5f}, {1, 1, 0}, "diagonal edges xy " + std::to_string(f)) > 0;
    }
    // Space diagonals pass through a corner of every cell they cross, in all 8 directions.
    for (int s = 0; s < 8; ++s) {
        const core::Vec3 d{s & 1 ? -1.0f : 1.0f, s & 2 ? -1.0f : 1.0f, s & 4 ? -1.0f : 1.0f};
        const core::Vec3 o{s & 1 ? 2.0f : -1.0f, s & 2 ? 2.0f : -1.0f, s & 4 ? 2.0f : -1.0f};
        const std::size_t k = check_walk(tree, o, core::normalize(d), "corner diagonal " + std::to_string(s));
        EXPECT_GE(k, 16u);  // crosses at least one cell per level-4 slab
        ++n;
    }
    // Rays starting exactly on faces, edges and corners, inside the tree.
    n += check_walk(tree, {0.5f, 0.5f, 0.5f}, core::normalize({1, 1, 1}), "from the centre corner") > 0;
    n += check_walk(tree, {0.25f, 0.5f, 0.125f}, core::normalize({-1, 0.5f, 0}), "from an edge") > 0;
    n +=
        check_walk(tree, {1.0f, 1.0f, 1.0f}, core::normalize({-1, -1, -1}), "from the root's far corner") > 0;
    EXPECT_GT(n, 80);
}

TEST(OctreeWalk, DeepTree) {
    // Points closing in geometrically on a spot: each halving of the distance adds a level.
    std::vector<D3> pts{{0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}};
    const D3 spot{0.7, 0.35, 0.55};
    for (int k = 1; k <= 24; ++k) {
        const double e = std::ldexp(1.0, -k);
        pts.push_back({spot[0] + e, spot[1] + e * 0.5, spot[2] - e * 0.25});
    }
    const TestOctree tree = build_test_octree(point_splats(pts, 1e-9f), {0, 0, 0}, 1.0, 1, 26);
    ASSERT_GE(tree.info.depth, 20u) << "the test tree is not deep enough";
    std::uint32_t deepest = 0;
    int rays = 0;
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int i = 0; i < 200; ++i) {
        // Rays aimed at the spot (within a few deep cells of it) from all around.
        D3 from{u(rng), u(rng), u(rng)};
        from = d3_add(spot, d3_mul(d3_norm(from), 1.5));
        const D3 at = d3_add(spot, {1e-7 * u(rng), 1e-7 * u(rng), 1e-7 * u(rng)});
        const D3 d = d3_norm(d3_sub(at, from));
        const Walked w = walk(tree.view(), fv(from), fv(d));
        for (const auto& l : w.leaves) deepest = std::max(deepest, l.level);
        check_walk(tree, fv(from), fv(d), "deep ray " + std::to_string(i));
        ++rays;
    }
    EXPECT_GE(deepest, 18u) << "no ray reached the deep leaves";
    // Axis-parallel rays through the spot itself.
    check_walk(tree, fv({-1.0, spot[1], spot[2]}), {1, 0, 0}, "deep x");
    check_walk(tree, fv({spot[0], 2.0, spot[2]}), {0, -1, 0}, "deep -y");
}

TEST(OctreeWalk, StepBoundEndsTheWalk) {
    const TestOctree tree = random_tree(1.0, {0, 0, 0}, 6, 2000);
    const Walked full = walk(tree.view(), {-1, 0.31f, 0.62f}, {1, 0, 0});
    ASSERT_GT(full.leaves.size(), 5u);
    EXPECT_FALSE(full.truncated);
    const Walked cut = walk(tree.view(), {-1, 0.31f, 0.62f}, {1, 0, 0}, core::k_inf, 3);
    EXPECT_EQ(cut.leaves.size(), 3u);
    EXPECT_TRUE(cut.truncated);
}

TEST(OctreeWalk, RejectsNonFiniteRaysAndMisses) {
    const TestOctree tree = random_tree(1.0, {0, 0, 0}, 7);
    EXPECT_FALSE(walk(tree.view(), {std::nanf(""), 0, 0}, {1, 0, 0}).began);
    EXPECT_FALSE(walk(tree.view(), {0.5f, 0.5f, -1}, {0, 0, 0}).began);  // zero direction outside
    EXPECT_FALSE(walk(tree.view(), {-1, 2, 0.5f}, {1, 0, 0}).began);     // passes above the root
    EXPECT_FALSE(walk(tree.view(), {2, 0.5f, 0.5f}, {1, 0, 0}).began);   // points away
    // t_max before the root: no leaves.
    EXPECT_TRUE(walk(tree.view(), {-1, 0.5f, 0.5f}, {1, 0, 0}, 0.5f).leaves.empty());
}

TEST(OctreeWalk, CorruptAddressesEndInEmptyLeaves) {
    // An internal root pointing past the node array must not be followed.
    std::vector<std::uint32_t> nodes{pool::make_node(pool::NodeType::internal, 5)};
    std::vector<std::uint32_t> leaf_info{0};
    core::OctreeView v;
    v.nodes = nodes.data();
    v.node_count = 1;
    v.leaf_info = leaf_info.data();
    v.filled_leaves = 0;
    const Walked w = walk(v, {-1, 0.5f, 0.5f}, {1, 0, 0});
    ASSERT_EQ(w.leaves.size(), 1u);
    EXPECT_FALSE(core::node_is_filled(w.leaves[0].node));
}

// The shadow rays' upper bound (splat.h, bricks.h: t_max one ulp toward zero) on the bits, against
// libm's nextafterf on random bit patterns (every sign, exponent, subnormals, NaN, inf) and the edges.
TEST(CoreMath, NextTowardZeroIsNextafterfTowardZero) {
    const auto same = [](float a, float b) {
        if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
        std::uint32_t x, y;
        std::memcpy(&x, &a, 4);
        std::memcpy(&y, &b, 4);
        return x == y;  // +0 and -0 apart
    };
    const float lim = std::numeric_limits<float>::max(), tiny = std::numeric_limits<float>::denorm_min();
    for (float x : {0.0f, -0.0f, tiny, -tiny, std::numeric_limits<float>::min(), 1.0f, -1.0f, lim, -lim,
                    core::k_inf, -core::k_inf, std::numeric_limits<float>::quiet_NaN()})
        EXPECT_TRUE(same(core::next_toward_zero(x), std::nextafter(x, 0.0f))) << x;
    std::mt19937 rng(5);
    for (int i = 0; i < 200000; ++i) {
        const std::uint32_t bits = static_cast<std::uint32_t>(rng());
        float x;
        std::memcpy(&x, &bits, 4);
        ASSERT_TRUE(same(core::next_toward_zero(x), std::nextafter(x, 0.0f))) << std::hex << bits;
    }
}

}  // namespace
}  // namespace prt::test
