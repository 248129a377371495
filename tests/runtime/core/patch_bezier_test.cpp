// prt/core/bezier.h against independent references: the matrix form of seed 002 eq. 1, finite
// differences, re-evaluation of de Casteljau halves, and the builder's boxes and normal cones
// against surface samples.
#include "prt/core/bezier.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "patch_build.h"
#include "patch_test_util.h"

namespace {

using namespace prt::patch_test;
using prt::core::DVec3;

double dist(const V3& a, const V3& b) {
    return norm3(sub(a, b));
}

TEST(Bezier, EvaluationMatchesMatrixForm) {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    for (int n = 0; n < 20; ++n) {
        const Net net = random_net(rng, 3.0);
        for (int s = 0; s < 20; ++s) {
            const double u = uni(rng), v = uni(rng);
            const auto e = prt::core::patch_eval(net, u, v);
            const MatrixEval m = matrix_eval(net, u, v);
            EXPECT_LT(dist(v3(e.q), m.q), 1e-13);
            EXPECT_LT(dist(v3(e.qu), m.qu), 1e-12);
            EXPECT_LT(dist(v3(e.qv), m.qv), 1e-12);
            // d2Q/dudv by central differences of dQ/dv
            const double h = 1e-5;
            const V3 fd = mul(sub(matrix_eval(net, u + h, v).qv, matrix_eval(net, u - h, v).qv), 0.5 / h);
            EXPECT_LT(dist(v3(e.quv), fd), 1e-7);
        }
    }
}

TEST(Bezier, CornersInterpolateTheNet) {
    std::mt19937_64 rng(2);
    const Net net = random_net(rng);
    EXPECT_LT(dist(v3(prt::core::patch_eval(net, 0, 0).q), v3(net.p[0])), 1e-15);
    EXPECT_LT(dist(v3(prt::core::patch_eval(net, 1, 0).q), v3(net.p[12])), 1e-15);
    EXPECT_LT(dist(v3(prt::core::patch_eval(net, 0, 1).q), v3(net.p[3])), 1e-15);
    EXPECT_LT(dist(v3(prt::core::patch_eval(net, 1, 1).q), v3(net.p[15])), 1e-15);
}

TEST(Bezier, DeCasteljauHalvesReproduceThePatch) {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    for (int axis = 0; axis < 2; ++axis)
        for (double t : {0.5, 0.3}) {
            const Net net = random_net(rng);
            Net lo{}, hi{};
            prt::core::patch_split(net, axis, t, lo, hi);
            for (int s = 0; s < 50; ++s) {
                const double a = uni(rng), b = uni(rng);
                // lower half: parameter a along the split axis maps to t a; upper: t + (1 - t) a
                const double ul = axis == 0 ? t * a : a, vl = axis == 0 ? b : t * b;
                const double uh = axis == 0 ? t + (1 - t) * a : a, vh = axis == 0 ? b : t + (1 - t) * b;
                EXPECT_LT(dist(matrix_eval(lo, a, b).q, matrix_eval(net, ul, vl).q), 1e-13);
                EXPECT_LT(dist(matrix_eval(hi, a, b).q, matrix_eval(net, uh, vh).q), 1e-13);
            }
        }
}

TEST(Bezier, SubpatchDomainsTileTheSquareAlternatingUV) {
    using prt::core::subpatch_domain;
    for (std::uint32_t depth = 0; depth <= 7; ++depth) {
        const std::uint32_t first = (1u << depth) - 1, last = (2u << depth) - 2;
        // leaves: cells of a 2^ceil(d/2) x 2^floor(d/2) grid (u split first), each exactly once
        const std::uint32_t nu = 1u << ((depth + 1) / 2), nv = 1u << (depth / 2);
        std::vector<int> hits(nu * nv, 0);
        for (std::uint32_t k = first; k <= last; ++k) {
            const auto d = subpatch_domain(k);
            EXPECT_DOUBLE_EQ(d.u1 - d.u0, 1.0 / nu);
            EXPECT_DOUBLE_EQ(d.v1 - d.v0, 1.0 / nv);
            ++hits[std::uint32_t(d.u0 * nu) * nv + std::uint32_t(d.v0 * nv)];
        }
        for (int h : hits) EXPECT_EQ(h, 1);
    }
    // children halve their parent along u at even levels and along v at odd levels
    for (std::uint32_t k = 0; k < 63; ++k) {
        const auto p = subpatch_domain(k), a = subpatch_domain(2 * k + 1), b = subpatch_domain(2 * k + 2);
        const std::uint32_t level = prt::core::subpatch_level(k);
        // the split parameter (u at even levels, v at odd ones) and the kept one, as [lo, hi] members
        using D = prt::core::PatchDomain;
        const bool even = level % 2 == 0;
        double D::*const s0 = even ? &D::u0 : &D::v0;
        double D::*const s1 = even ? &D::u1 : &D::v1;
        double D::*const k0 = even ? &D::v0 : &D::u0;
        double D::*const k1 = even ? &D::v1 : &D::u1;
        EXPECT_EQ(a.*s0, p.*s0) << "k " << k;
        EXPECT_EQ(a.*s1, 0.5 * (p.*s0 + p.*s1)) << "k " << k;
        EXPECT_EQ(b.*s0, a.*s1) << "k " << k;
        EXPECT_EQ(b.*s1, p.*s1) << "k " << k;
        EXPECT_EQ(a.*k0, p.*k0) << "k " << k;
        EXPECT_EQ(a.*k1, p.*k1) << "k " << k;
    }
}

TEST(Bezier, SubpatchTreeBoxesAndConesBoundTheirPieceOfSurface) {
    std::mt19937_64 rng(4);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    const std::uint32_t depth = 4, count = (2u << depth) - 1;
    int cones = 0;
    for (int n = 0; n < 10; ++n) {
        const Net net = random_net(rng, 2.0);
        std::vector<prt::pool::SubpatchNode> nodes(count);
        prt::patches::build_subpatch_tree(net, depth, 0.0, nodes.data());
        for (std::uint32_t k = 0; k < count; ++k) {
            const auto d = prt::core::subpatch_domain(k);
            const auto& node = nodes[k];
            const DVec3 axis = prt::core::octahedral_decode(node.cone_axis);
            cones += node.cone_cos > 0;
            for (int s = 0; s < 30; ++s) {
                const double u = d.u0 + (d.u1 - d.u0) * uni(rng), v = d.v0 + (d.v1 - d.v0) * uni(rng);
                const MatrixEval e = matrix_eval(net, u, v);
                for (int a = 0; a < 3; ++a) {
                    EXPECT_LE(node.lo[a], e.q[a]);
                    EXPECT_GE(node.hi[a], e.q[a]);
                }
                if (node.cone_cos > 0) {
                    const V3 nrm = unit3(cross3(e.qu, e.qv));
                    EXPECT_GE(dot3(nrm, v3(axis)), node.cone_cos) << "node " << k;
                }
            }
        }
    }
    EXPECT_GT(cones, int(count) * 10 / 2);  // most nodes of these gently curved patches have a cone
}

TEST(Bezier, OctahedralRoundTrip) {
    std::mt19937_64 rng(5);
    std::normal_distribution<double> g;
    for (int i = 0; i < 2000; ++i) {
        const V3 n = unit3({g(rng), g(rng), g(rng)});
        const DVec3 d = prt::core::octahedral_decode(prt::core::octahedral_encode(dv(n)));
        EXPECT_NEAR(prt::core::length(d), 1.0, 1e-12);
        EXPECT_GT(dot3(v3(d), n), std::cos(1e-4));
    }
}

TEST(Bezier, NormalIsUnitCrossProductAtRegularPoints) {
    std::mt19937_64 rng(6);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    const Net net = random_net(rng);
    for (int s = 0; s < 100; ++s) {
        const double u = uni(rng), v = uni(rng);
        const auto e = prt::core::patch_eval(net, u, v);
        const DVec3 n = prt::core::patch_normal(net, u, v, e, DVec3{0, 0, 0});
        const MatrixEval m = matrix_eval(net, u, v);
        EXPECT_LT(dist(v3(n), unit3(cross3(m.qu, m.qv))), 1e-12);
    }
}

/// A cone-like patch: the edge v = 0 collapsed to the apex (0,0,1) (the teapot lid's top).
Net collapsed_net() {
    Net n{};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            const double ang = 1.5707963267948966 * i / 3.0;  // a quarter turn along u
            const double r = j / 3.0;
            n.p[4 * i + j] = {r * std::cos(ang), r * std::sin(ang), 1.0 - 0.5 * r};
        }
    return n;
}

TEST(Bezier, NormalAtACollapsedEdgeIsTheLimitFromInside) {
    const Net net = collapsed_net();
    for (double u : {0.0, 0.2, 0.5, 0.9, 1.0}) {
        const auto e0 = prt::core::patch_eval(net, u, 0.0);
        EXPECT_LT(prt::core::length(e0.qu), 1e-14);  // dQ/du vanishes on the collapsed edge
        const DVec3 n0 = prt::core::patch_normal(net, u, 0.0, e0, DVec3{0, 0, 0});
        ASSERT_NEAR(prt::core::length(n0), 1.0, 1e-12);
        // the regular normal slightly inside the patch
        const MatrixEval m = matrix_eval(net, u, 1e-4);
        const V3 inside = unit3(cross3(m.qu, m.qv));
        EXPECT_GT(dot3(v3(n0), inside), std::cos(1e-3)) << "u = " << u;
    }
}

TEST(Bezier, NormalOfAFullyDegeneratePatchIsTheFallback) {
    Net net{};
    for (auto& p : net.p) p = {1, 2, 3};
    const auto e = prt::core::patch_eval(net, 0.3, 0.6);
    const DVec3 n = prt::core::patch_normal(net, 0.3, 0.6, e, DVec3{0, 1, 0});
    EXPECT_EQ(n.x, 0.0);
    EXPECT_EQ(n.y, 1.0);
    EXPECT_EQ(n.z, 0.0);
}

TEST(Bezier, NormalConeOfAPlaneIsItsNormal) {
    const Net net = planar_net({0, 0, 0}, {2, 0, 0}, {0, 1, 1});
    const auto cone = prt::patches::normal_cone(net);
    ASSERT_TRUE(cone.valid);
    const V3 expect = unit3(cross3({2, 0, 0}, {0, 1, 1}));
    EXPECT_NEAR(dot3({cone.axis[0], cone.axis[1], cone.axis[2]}, expect), 1.0, 1e-12);
    EXPECT_LT(cone.half_angle, 1e-7);
    // normals of a transposed patch point the other way
    const auto flipped = prt::patches::normal_cone(prt::patches::transpose_net(net));
    EXPECT_NEAR(dot3({flipped.axis[0], flipped.axis[1], flipped.axis[2]}, expect), -1.0, 1e-12);
}

}  // namespace
