// Shared helpers of the MLS tests: point sets with exact normals, and the independent references:
// F evaluated directly from WS05 eq. 2 in double precision over ALL splats (no kd-tree, no leaf
// lists, the paper's literal form W x - sum w p), and a brute-force root finder along a ray
// (dense sampling of that F, then bisection in double).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <span>
#include <vector>

#include "d3_math.h"
#include "mls_build.h"
#include "mls_pool.h"
#include "prt/core/mls.h"
#include "prt/formats/pool_layout.h"

namespace prt::mls_test {

using test::D3;
using test::d3;
using test::dot3;
using test::norm3;

/// Points with normals and splat radii (the inputs of build_mls).
struct PointSet {
    std::vector<pool::Float3> positions, normals;
    std::vector<float> radii;
};

/// A sphere of radius `r` centred at `c`, `n` points on a Fibonacci spiral (near-uniform), exact
/// outward normals, every radius the distance that holds ~10 points in its disk on a uniform
/// sampling (what prt-radii's k = 9 gives): r_splat = sqrt(10 / (pi density)).
inline PointSet fibonacci_sphere(std::size_t n, double r = 1.0, D3 c = {0, 0, 0}) {
    PointSet s;
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    const double density = double(n) / (4.0 * M_PI * r * r);
    const auto splat = static_cast<float>(std::sqrt(10.0 / (M_PI * density)));
    for (std::size_t i = 0; i < n; ++i) {
        const double y = 1.0 - 2.0 * (double(i) + 0.5) / double(n);
        const double rr = std::sqrt(1.0 - y * y);
        const double a = golden * double(i);
        const D3 u{std::cos(a) * rr, y, std::sin(a) * rr};
        s.positions.push_back({float(c[0] + r * u[0]), float(c[1] + r * u[1]), float(c[2] + r * u[2])});
        s.normals.push_back({float(u[0]), float(u[1]), float(u[2])});
        s.radii.push_back(splat);
    }
    return s;
}

/// WS05 eq. 1-2 by brute force over every splat, in double: F = (W x - sum w p) . sum w n.
struct BruteF {
    double f = 0, w = 0;
    D3 n{0, 0, 0};
};
inline BruteF brute_f(std::span<const pool::MlsSplat> splats, const D3& x) {
    BruteF r;
    D3 wp{0, 0, 0};
    for (const pool::MlsSplat& s : splats) {
        const D3 p = d3(s.position);
        const double d = std::sqrt((x[0] - p[0]) * (x[0] - p[0]) + (x[1] - p[1]) * (x[1] - p[1]) +
                                   (x[2] - p[2]) * (x[2] - p[2]));
        const double rr = d * double(s.inv_support);
        if (rr >= 1.0) continue;
        const double w = 1.0 - rr;
        r.w += w;
        for (int a = 0; a < 3; ++a) {
            wp[a] += w * p[a];
            r.n[a] += w * double(a == 0 ? s.normal.x : a == 1 ? s.normal.y : s.normal.z);
        }
    }
    r.f = (r.w * x[0] - wp[0]) * r.n[0] + (r.w * x[1] - wp[1]) * r.n[1] + (r.w * x[2] - wp[2]) * r.n[2];
    return r;
}

/// The first root of the brute-force F along o + t d in [t0, t1] (a sign change between two of
/// `samples` regular samples with W > 0 at both, bisected to double precision), or -1.
inline double brute_root(std::span<const pool::MlsSplat> splats, const D3& o, const D3& d, double t0,
                         double t1, int samples = 4000) {
    auto at = [&](double t) { return D3{o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]}; };
    double prev_t = t0;
    BruteF prev = brute_f(splats, at(t0));
    for (int i = 1; i <= samples; ++i) {
        const double t = t0 + (t1 - t0) * double(i) / double(samples);
        const BruteF cur = brute_f(splats, at(t));
        if (prev.w > 0 && cur.w > 0 && ((prev.f > 0 && cur.f <= 0) || (prev.f < 0 && cur.f >= 0))) {
            double a = prev_t, b = t, fa = prev.f;
            for (int k = 0; k < 80; ++k) {
                const double m = 0.5 * (a + b);
                const BruteF fm = brute_f(splats, at(m));
                if ((fm.f > 0) == (fa > 0)) {
                    a = m;
                    fa = fm.f;
                } else {
                    b = m;
                }
            }
            return 0.5 * (a + b);
        }
        prev = cur;
        prev_t = t;
    }
    return -1.0;
}

/// Every leaf of a built tree with its cell (walked from the root, independent of the core).
struct LeafCell {
    std::uint32_t node;
    mls::Box cell;
    std::uint32_t first, count;
};
inline std::vector<LeafCell> leaf_cells(const mls::MlsModel& m) {
    std::vector<LeafCell> out;
    struct Item {
        std::uint32_t node;
        mls::Box cell;
    };
    mls::Box root{};
    for (int a = 0; a < 3; ++a) {
        root.lo[a] = m.info.root_lo[a];
        root.hi[a] = m.info.root_hi[a];
    }
    std::vector<Item> stack{{0, root}};
    while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        const pool::MlsNode& n = m.nodes[it.node];
        if (pool::mls_node_is_leaf(n)) {
            out.push_back({it.node, it.cell, pool::mls_leaf_first(n), pool::mls_leaf_count(n)});
            continue;
        }
        const int a = static_cast<int>(pool::mls_node_axis(n));
        const double split = core::mls_node_split(n);
        Item l = it, r = it;
        l.node = pool::mls_node_left(n);
        r.node = l.node + 1;
        l.cell.hi[a] = split;
        r.cell.lo[a] = split;
        stack.push_back(l);
        stack.push_back(r);
    }
    return out;
}

/// Squared distance from p to a box (0 inside).
inline double box_distance2(const D3& p, const mls::Box& b) {
    double d2 = 0;
    for (int a = 0; a < 3; ++a) {
        const double d = std::max({b.lo[a] - p[a], p[a] - b.hi[a], 0.0});
        d2 += d * d;
    }
    return d2;
}

/// A build with the tests' usual options (all cores, defaults otherwise).
inline mls::MlsModel build(const PointSet& s, mls::BuildOptions opt = {}) {
    return mls::build_mls(s.positions, s.normals, s.radii, opt);
}

}  // namespace prt::mls_test
