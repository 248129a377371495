// prt/core/patch.h: ray-patch intersection against analytic references (a plane, the saddle
// z = x y), misses, Newton's failure modes, the face and self-hit filters, and the equivalence of
// the per-ray traversal with early termination, an exhaustive search, and the data-parallel split.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "patch_test_util.h"
#include "prt/core/patch.h"

namespace {

using namespace prt::patch_test;
using prt::core::DVec3;
using prt::core::PatchHit;
using prt::core::PatchTraceParams;

bool all_finite(const PatchHit& h) {
    return std::isfinite(h.t) && std::isfinite(h.u) && std::isfinite(h.v) &&
           prt::core::is_finite(h.position) && prt::core::is_finite(h.normal);
}

TEST(PatchIntersect, PlanarPatchMatchesAnalyticPlane) {
    const V3 o{-1.0, 0.5, 2.0}, a{3.0, 0.5, 0.0}, b{0.2, 2.0, 1.0};
    const BuiltPool bp = build_pool({planar_net(o, a, b)});
    const V3 n = unit3(cross3(a, b));
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> uni(0.0, 1.0), wide(-5.0, 5.0);
    const PatchTraceParams params;
    int hits = 0;
    for (int i = 0; i < 2000; ++i) {
        const double u = uni(rng), v = uni(rng);
        const V3 target = add(o, add(mul(a, u), mul(b, v)));
        V3 origin{wide(rng), wide(rng), wide(rng)};
        if (std::fabs(dot3(sub(origin, target), n)) < 0.2) origin = add(origin, mul(n, 1.0));  // not grazing
        const V3 dir = mul(sub(target, origin), 0.37);  // not unit: t = 1 / 0.37 at the target
        PatchHit h;
        ASSERT_TRUE(prt::core::trace_patches(bp.view, local_ray(bp, origin, dir), params, h)) << i;
        ++hits;
        EXPECT_NEAR(h.t, 1.0 / 0.37, 1e-9 * (1.0 / 0.37));
        EXPECT_NEAR(h.u, u, 1e-9);
        EXPECT_NEAR(h.v, v, 1e-9);
        EXPECT_NEAR(std::fabs(dot3(v3(h.normal), n)), 1.0, 1e-12);
        EXPECT_GT(dot3(v3(h.normal), n), 0.0);  // dQ/du x dQ/dv = a x b
        EXPECT_EQ(h.front, dot3(dir, n) < 0 ? 1u : 0u);
        EXPECT_EQ(h.patch, 0u);
    }
    EXPECT_EQ(hits, 2000);
}

TEST(PatchIntersect, PlanarPatchWithCurvedParametrization) {
    // All control points in the plane z = 1, the interior ones moved within it: the parametrization
    // is no longer linear, but every hit must lie on the ray, in the plane, with normal +-z.
    Net net = planar_net({0, 0, 1}, {1, 0, 0}, {0, 1, 0});
    net.p[5] = {0.45, 0.25, 1.0};
    net.p[10] = {0.5, 0.8, 1.0};
    net.p[6] = {0.2, 0.7, 1.0};
    const BuiltPool bp = build_pool({net});
    std::mt19937_64 rng(8);
    std::uniform_real_distribution<double> uni(0.1, 0.9);
    for (int i = 0; i < 500; ++i) {
        const MatrixEval e = matrix_eval(net, uni(rng), uni(rng));
        const V3 origin{uni(rng) * 4 - 2, uni(rng) * 4 - 2, 3.0};
        const V3 dir = unit3(sub(e.q, origin));
        PatchHit h;
        ASSERT_TRUE(prt::core::trace_patches(bp.view, local_ray(bp, origin, dir), PatchTraceParams{}, h));
        const double t_plane = (1.0 - origin[2]) / dir[2];
        EXPECT_NEAR(h.t, t_plane, 1e-10);
        EXPECT_NEAR(std::fabs(h.normal.z), 1.0, 1e-12);
        const MatrixEval at = matrix_eval(net, h.u, h.v);  // the reported (u, v) is the hit point
        EXPECT_LT(norm3(sub(at.q, add(origin, mul(dir, h.t)))), 1e-9);
    }
}

TEST(PatchIntersect, RaysOutsideThePatchOrParallelMiss) {
    const BuiltPool bp = build_pool({planar_net({0, 0, 0}, {1, 0, 0}, {0, 1, 0})});
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<double> out(0.0005, 0.5), in(0.0, 1.0);
    for (int i = 0; i < 500; ++i) {
        // just beyond the edge u = 1, or just before the edge v = 0
        const V3 target = (i % 2) ? V3{1.0 + out(rng), in(rng), 0} : V3{in(rng), -out(rng), 0};
        const V3 origin{0.5, 0.5, 2.0};
        PatchHit h;
        EXPECT_FALSE(prt::core::trace_patches(bp.view, local_ray(bp, origin, sub(target, origin)),
                                              PatchTraceParams{}, h))
            << target[0] << " " << target[1];
    }
    // parallel to the plane, in it and above it; pointing away; zero and NaN directions
    PatchHit h;
    EXPECT_FALSE(
        prt::core::trace_patches(bp.view, local_ray(bp, {-1, 0.5, 0.0}, {1, 0, 0}), PatchTraceParams{}, h));
    EXPECT_FALSE(
        prt::core::trace_patches(bp.view, local_ray(bp, {-1, 0.5, 0.1}, {1, 0, 0}), PatchTraceParams{}, h));
    EXPECT_FALSE(
        prt::core::trace_patches(bp.view, local_ray(bp, {0.5, 0.5, 1.0}, {0, 0, 1}), PatchTraceParams{}, h));
    EXPECT_FALSE(
        prt::core::trace_patches(bp.view, local_ray(bp, {0.5, 0.5, 1.0}, {0, 0, 0}), PatchTraceParams{}, h));
    EXPECT_FALSE(prt::core::trace_patches(bp.view, local_ray(bp, {0.5, 0.5, 1.0}, {0, NAN, -1}),
                                          PatchTraceParams{}, h));
    // t_max before the plane
    EXPECT_FALSE(prt::core::trace_patches(bp.view, local_ray(bp, {0.5, 0.5, 1.0}, {0, 0, -1}, 0.999),
                                          PatchTraceParams{}, h));
    EXPECT_TRUE(prt::core::trace_patches(bp.view, local_ray(bp, {0.5, 0.5, 1.0}, {0, 0, -1}, 1.001),
                                         PatchTraceParams{}, h));
}

/// Analytic nearest hit of a ray with z = x y, 0 <= x, y <= 1: (o + t d)_z = (o + t d)_x (o + t d)_y.
bool saddle_hit(const V3& o, const V3& d, double& t_hit, double& margin) {
    const double a = d[0] * d[1], b = o[0] * d[1] + o[1] * d[0] - d[2], c = o[0] * o[1] - o[2];
    double roots[2];
    int n = 0;
    if (std::fabs(a) < 1e-14) {
        if (std::fabs(b) > 1e-14) roots[n++] = -c / b;
    } else {
        const double disc = b * b - 4 * a * c;
        if (disc < 0) return false;
        const double s = std::sqrt(disc);
        const double q = -0.5 * (b + (b >= 0 ? s : -s));  // stable quadratic roots
        roots[n++] = q / a;
        if (q != 0) roots[n++] = c / q;
    }
    t_hit = INFINITY;
    margin = INFINITY;
    for (int i = 0; i < n; ++i) {
        const double t = roots[i];
        if (!(t > 0)) continue;
        const double x = o[0] + t * d[0], y = o[1] + t * d[1];
        const double m = std::min(std::min(x, 1 - x), std::min(y, 1 - y));  // distance inside the square
        if (m < -1e-12) continue;
        if (t < t_hit) t_hit = t, margin = m;
    }
    return std::isfinite(t_hit);
}

TEST(PatchIntersect, SaddleMatchesAnalyticQuadratic) {
    const BuiltPool bp = build_pool({saddle_net()});
    std::mt19937_64 rng(10);
    std::uniform_real_distribution<double> uni(-0.2, 1.2), side(-2.0, 2.0);
    int both = 0, grazing_skipped = 0;
    for (int i = 0; i < 4000; ++i) {
        const V3 target{uni(rng), uni(rng), uni(rng) - 0.1};
        const V3 origin{side(rng), side(rng), (i % 2) ? 2.5 : -1.5};
        const V3 dir = unit3(sub(target, origin));
        double t_ref = 0, margin = 0;
        const bool ref = saddle_hit(origin, dir, t_ref, margin);
        PatchHit h;
        const bool got = prt::core::trace_patches(bp.view, local_ray(bp, origin, dir), PatchTraceParams{}, h);
        if (ref && margin > 1e-6) {
            // the analytic normal (-y, -x, 1): reject grazing rays, where the root is ill-conditioned
            const V3 p = add(origin, mul(dir, t_ref));
            const V3 n = unit3({-p[1], -p[0], 1.0});
            if (std::fabs(dot3(n, dir)) < 0.02) {
                ++grazing_skipped;
                continue;
            }
            ASSERT_TRUE(got) << "missed analytic hit, ray " << i;
            ++both;
            EXPECT_NEAR(h.t, t_ref, 1e-9) << i;
            EXPECT_NEAR(std::fabs(dot3(v3(h.normal), n)), 1.0, 1e-9);
            EXPECT_NEAR(h.u, p[0], 1e-9);
            EXPECT_NEAR(h.v, p[1], 1e-9);
        } else if (!ref) {
            EXPECT_FALSE(got) << "hit where the quadratic has no root in the square, ray " << i;
        }
        if (got) {
            EXPECT_TRUE(all_finite(h));
        }
    }
    EXPECT_GT(both, 1000);
    EXPECT_LT(grazing_skipped, 40);
}

TEST(PatchIntersect, EverySubpatchDepthFindsTheSameHits) {
    // Depth 0 (Newton from the patch centre only) up to the deepest tree the format allows.
    std::mt19937_64 rng(22);
    std::uniform_real_distribution<double> uni(0.05, 0.95);
    std::vector<std::pair<V3, V3>> rays;
    for (int i = 0; i < 200; ++i) {
        const V3 target{uni(rng), uni(rng), 0.0};
        const V3 p{target[0], target[1], target[0] * target[1]};  // on the saddle
        const V3 origin{uni(rng) * 2 - 0.5, uni(rng) * 2 - 0.5, 2.0};
        rays.push_back({origin, unit3(sub(p, origin))});
    }
    for (std::uint32_t depth : {0u, 1u, 2u, 5u, 10u}) {
        const BuiltPool bp = build_pool({saddle_net()}, depth);
        EXPECT_EQ(bp.view.subpatch_nodes, (2u << depth) - 1);
        for (const auto& [o, d] : rays) {
            double t_ref = 0, margin = 0;
            ASSERT_TRUE(saddle_hit(o, d, t_ref, margin));
            PatchHit h;
            ASSERT_TRUE(prt::core::trace_patches(bp.view, local_ray(bp, o, d), PatchTraceParams{}, h))
                << depth;
            EXPECT_NEAR(h.t, t_ref, 1e-9) << "depth " << depth;
        }
    }
}

TEST(PatchIntersect, SaddleCrossedTwiceGivesTheNearerRoot) {
    // Along x = y = s the saddle is z = s^2; the line z = -0.1 + 0.9 s meets it at s ~ 0.1298 and
    // s ~ 0.7702, both inside the square.
    const BuiltPool bp = build_pool({saddle_net()});
    const double s1 = (0.9 - std::sqrt(0.81 - 0.4)) / 2, s2 = (0.9 + std::sqrt(0.81 - 0.4)) / 2;
    const V3 d = unit3({1, 1, 0.9});
    const double scale = std::sqrt(2 + 0.81);  // |(1,1,0.9)|: distance per unit of s
    PatchHit h;
    ASSERT_TRUE(prt::core::trace_patches(bp.view, local_ray(bp, {0, 0, -0.1}, d), PatchTraceParams{}, h));
    EXPECT_NEAR(h.t, s1 * scale, 1e-10);
    ASSERT_TRUE(
        prt::core::trace_patches(bp.view, local_ray(bp, {1, 1, 0.8}, mul(d, -1)), PatchTraceParams{}, h));
    EXPECT_NEAR(h.t, (1 - s2) * scale, 1e-10);
    // both roots lie on one ray: an occlusion query with t_max between them
    EXPECT_TRUE(prt::core::patches_occluded(bp.view, local_ray(bp, {0, 0, -0.1}, d, s1 * scale + 1e-6),
                                            PatchTraceParams{}));
    EXPECT_FALSE(prt::core::patches_occluded(bp.view, local_ray(bp, {0, 0, -0.1}, d, s1 * scale - 1e-6),
                                             PatchTraceParams{}));
}

TEST(PatchIntersect, NewtonReportsItsFailureModes) {
    const Net plane = planar_net({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
    PatchTraceParams p;
    // a ray parallel to the plane: the Jacobian is singular
    auto planes = prt::core::make_ray_planes({-1, 0.5, 0.2}, {1, 0, 0});
    auto r = prt::core::patch_newton(plane, planes, 0.5, 0.5, p, 1e-12);
    EXPECT_EQ(r.status, prt::core::NewtonStatus::singular);
    // the line meets the plane's extension at u = 3: Newton (exact for a plane) leaves the domain
    planes = prt::core::make_ray_planes({3, 0.5, 1}, {0, 0, -1});
    r = prt::core::patch_newton(plane, planes, 0.5, 0.5, p, 1e-12);
    EXPECT_EQ(r.status, prt::core::NewtonStatus::left_domain);
    // inside: converges in one step (R is linear in u, v)
    planes = prt::core::make_ray_planes({0.25, 0.75, 1}, {0, 0, -1});
    r = prt::core::patch_newton(plane, planes, 0.5, 0.5, p, 1e-12);
    EXPECT_EQ(r.status, prt::core::NewtonStatus::converged);
    EXPECT_EQ(r.iterations, 1u);
    EXPECT_NEAR(r.u, 0.25, 1e-15);
    EXPECT_NEAR(r.v, 0.75, 1e-15);
    // heading for a known root: stops when within the radius of it
    r = prt::core::patch_newton(plane, planes, 0.5, 0.5, p, 1e-12, 0.25, 0.75, 1e-4);
    EXPECT_EQ(r.status, prt::core::NewtonStatus::known_root);
    EXPECT_EQ(r.iterations, 1u);
    r = prt::core::patch_newton(plane, planes, 0.5, 0.5, p, 1e-12, 0.3, 0.75, 1e-4);  // another root
    EXPECT_EQ(r.status, prt::core::NewtonStatus::converged);
    // no more steps than allowed
    p.max_iterations = 0;
    planes = prt::core::make_ray_planes({0.3, 0.3, 1}, {0, 0, -1});
    r = prt::core::patch_newton(saddle_net(), planes, 0.9, 0.9, p, 1e-12);
    EXPECT_EQ(r.status, prt::core::NewtonStatus::no_convergence);
    EXPECT_EQ(r.iterations, 0u);
}

TEST(PatchIntersect, FaceFilterFollowsTheRayFlag) {
    // normal a x b = +z
    const BuiltPool bp = build_pool({planar_net({0, 0, 0}, {1, 0, 0}, {0, 1, 0})});
    PatchTraceParams p;
    p.faces = prt::core::k_patch_faces_by_ray;
    PatchHit h;
    EXPECT_TRUE(prt::core::trace_patches(bp.view, local_ray(bp, {0.5, 0.5, 1}, {0, 0, -1}), p, h));  // front
    EXPECT_EQ(h.front, 1u);
    EXPECT_FALSE(prt::core::trace_patches(bp.view, local_ray(bp, {0.5, 0.5, -1}, {0, 0, 1}), p, h));  // back
    EXPECT_TRUE(
        prt::core::trace_patches(bp.view, local_ray(bp, {0.5, 0.5, -1}, {0, 0, 1}, 1e30, true), p, h));
    EXPECT_EQ(h.front, 0u);
    EXPECT_FALSE(
        prt::core::trace_patches(bp.view, local_ray(bp, {0.5, 0.5, 1}, {0, 0, -1}, 1e30, true), p, h));
    // both faces by default
    EXPECT_TRUE(
        prt::core::trace_patches(bp.view, local_ray(bp, {0.5, 0.5, -1}, {0, 0, 1}), PatchTraceParams{}, h));
}

TEST(PatchIntersect, SkipGuardIgnoresTheRaysOwnStartingPoint) {
    // A secondary ray leaving the saddle at s = 0.5 on the diagonal x = y = s (z = s^2) along the
    // line z = 0.25 + 0.6 (s - 0.5), towards decreasing s: it starts on the surface (a root at t = 0,
    // which rounding may put on either side) and meets the saddle again at s = 0.1.
    // The start is moved back along the ray by 1e-7, so the ray meets its own surface at t = 1e-7.
    const BuiltPool bp = build_pool({saddle_net()});
    const V3 dir = unit3({-1, -1, -0.6});
    const V3 start = sub(V3{0.5, 0.5, 0.25}, mul(dir, 1e-7));
    PatchTraceParams p;
    p.skip_patch = 0;
    p.skip_u = 0.5;
    p.skip_v = 0.5;
    PatchHit h;
    ASSERT_TRUE(prt::core::trace_patches(bp.view, local_ray(bp, start, dir), p, h));
    EXPECT_NEAR(h.u, 0.1, 1e-9);
    EXPECT_NEAR(h.v, 0.1, 1e-9);
    EXPECT_NEAR(h.t, 1e-7 + 0.4 * std::sqrt(2 + 0.36), 1e-9);
    // the guard is per patch: another patch index does not suppress the start point
    p.skip_patch = 1;
    ASSERT_TRUE(prt::core::trace_patches(bp.view, local_ray(bp, start, dir), p, h));
    EXPECT_NEAR(h.t, 1e-7, 1e-10);
}

/// A small scene of curved patches in a grid, some overlapping in depth.
std::vector<Net> scene_nets() {
    std::mt19937_64 rng(11);
    std::vector<Net> nets;
    for (int i = 0; i < 5; ++i)
        for (int j = 0; j < 5; ++j) {
            Net n = random_net(rng, 1.0);
            for (auto& p : n.p) p = {p.x + i * 0.8, p.y + j * 0.8, p.z + 0.3 * ((i + j) % 3)};
            nets.push_back(n);
        }
    return nets;
}

TEST(PatchIntersect, EarlyTerminationEqualsExhaustiveSearchOverHitLeaves) {
    const BuiltPool bp = build_pool(scene_nets(), 4);
    const auto& view = bp.view;
    std::mt19937_64 rng(12);
    std::uniform_real_distribution<double> uni(-0.5, 4.5);
    const PatchTraceParams params;
    int hits = 0;
    for (int i = 0; i < 1500; ++i) {
        const V3 origin{uni(rng), uni(rng), 3.0 + uni(rng)};
        const V3 target{uni(rng), uni(rng), 0.0};
        const auto ray = local_ray(bp, origin, sub(target, origin));
        PatchHit h;
        const bool got = prt::core::trace_patches(view, ray, params, h);
        // Exhaustive: Newton from every leaf whose box the ray meets, in every patch, no ordering.
        prt::core::PatchQuery q;
        ASSERT_TRUE(prt::core::make_patch_query(view, ray, params, false, q));
        PatchHit best;
        bool any = false;
        const std::uint32_t first_leaf = (1u << view.subpatch_depth) - 1;
        for (std::uint32_t p = 0; p < view.patch_count; ++p)
            for (std::uint32_t k = first_leaf; k < view.subpatch_nodes; ++k) {
                const auto& node = view.nodes[std::size_t(p) * view.subpatch_nodes + k];
                float tn;
                if (!prt::core::box_hit(q.box, node.lo, node.hi, INFINITY, tn)) continue;
                q.best_t = any ? best.t : ray.t_max;
                PatchHit c;
                if (prt::core::patch_leaf_newton(view, p, k, q, params, c, nullptr)) {
                    best = c;
                    any = true;
                }
            }
        ASSERT_EQ(got, any) << "ray " << i;
        if (got) {
            ++hits;
            // the same root, possibly reached from another leaf: equal up to the Newton tolerance
            EXPECT_NEAR(h.t, best.t, 1e-9) << "ray " << i;
            EXPECT_EQ(h.patch, best.patch);
        }
    }
    EXPECT_GT(hits, 500);
}

TEST(PatchIntersect, DataParallelSplitEqualsPerRayTraversal) {
    const BuiltPool bp = build_pool(scene_nets());
    const auto& view = bp.view;
    std::mt19937_64 rng(13);
    std::uniform_real_distribution<double> uni(-0.5, 4.5);
    const PatchTraceParams params;
    for (int i = 0; i < 1000; ++i) {
        const V3 origin{uni(rng), uni(rng), 3.0};
        const auto ray = local_ray(bp, origin, sub(V3{uni(rng), uni(rng), 0.0}, origin));
        PatchHit h;
        const bool got = prt::core::trace_patches(view, ray, params, h);
        // traverse kernel: candidates; recheck + newton per (ray, patch) pair
        std::uint32_t cand[64];
        float cand_t[64];
        const std::uint32_t n = prt::core::patch_bvh_candidates(view, ray, ray.t_max, cand, cand_t, 64);
        ASSERT_LE(n, 64u);
        prt::core::PatchQuery q;
        ASSERT_TRUE(prt::core::make_patch_query(view, ray, params, false, q));
        PatchHit best;
        bool any = false;
        for (std::uint32_t c = 0; c < n; ++c) {
            PatchHit ph;
            q.best_t = ray.t_max;  // each pair on its own, as a kernel thread would
            if (prt::core::intersect_patch(view, cand[c], cand_t[c], q, params, ph, nullptr) &&
                (!any || ph.t < best.t)) {
                best = ph;
                any = true;
            }
        }
        ASSERT_EQ(got, any) << i;
        if (got) {
            EXPECT_NEAR(h.t, best.t, 1e-9);
        }
        // shadow query agrees
        EXPECT_EQ(prt::core::patches_occluded(view, ray, params), got);
    }
}

TEST(PatchIntersect, StatisticsCountTheWork) {
    const BuiltPool bp = build_pool(scene_nets());
    prt::core::PatchStats st;
    PatchHit h;
    ASSERT_TRUE(prt::core::trace_patches(bp.view, local_ray(bp, {1.7, 1.7, 3}, {0, 0, -1}),
                                         PatchTraceParams{}, h, &st));
    EXPECT_GE(st.bvh_nodes, 1u);
    EXPECT_GE(st.patches, 1u);
    EXPECT_GE(st.subpatch_boxes, 2u * bp.view.subpatch_depth);
    EXPECT_GE(st.newton_runs, 1u);
    EXPECT_GE(st.newton_iterations, h.iterations);
    prt::core::PatchStats miss;
    EXPECT_FALSE(prt::core::trace_patches(bp.view, local_ray(bp, {1.7, 1.7, 3}, {0, 0, 1}),
                                          PatchTraceParams{}, h, &miss));
    EXPECT_EQ(miss.newton_runs, 0u);
}

}  // namespace
