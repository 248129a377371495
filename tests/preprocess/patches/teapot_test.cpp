// The Utah teapot (../shared/data/bezier) against an independent reference: every patch
// tessellated into a fine triangle grid (evaluated with the matrix form of seed 002 eq. 1 in
// patch_test_util.h) and intersected by brute force (Moeller-Trumbore in double). Also rays at
// silhouettes and at the collapsed (degenerate) lid and bottom points, orientation and culling.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>

#include "patch_file.h"
#include "patch_test_util.h"
#include "prt/core/patch.h"
#include "ray_reference.h"

namespace {

using namespace prt::patch_test;
using prt::core::PatchHit;
using prt::core::PatchTraceParams;

const std::string k_teapot = std::string(PRT_SHARED_DATA_DIR) + "/bezier/teapot";

#define REQUIRE_TEAPOT()                                  \
    if (!std::filesystem::exists(k_teapot))               \
    GTEST_SKIP() << "shared data not found: " << k_teapot \
                 << " (../shared/data/bezier is absent on this machine)"

std::vector<Net> teapot_nets() {
    return prt::patches::read_patch_file(k_teapot, prt::patches::PatchFormat::newell).nets;
}

// ---- The triangle reference -----------------------------------------------------------------------

/// Each patch as an N x N grid of parameter cells, two triangles per cell, with the bound delta on
/// the distance between the patch and its tessellation (derivation in tessellation_bound()).
class TriangleReference {
public:
    TriangleReference(const std::vector<Net>& nets, int n) : m_n(n) {
        for (const Net& net : nets) {
            Patch p;
            p.grid.resize(std::size_t(n + 1) * (n + 1));
            for (int i = 0; i <= n; ++i)
                for (int j = 0; j <= n; ++j)
                    p.grid[i * (n + 1) + j] = matrix_eval(net, double(i) / n, double(j) / n).q;
            p.delta = tessellation_bound(net, 1.0 / n);
            // boxes of each strip of cells with one u index, grown by delta: the surface lies in them
            p.strip_lo.assign(n, {INFINITY, INFINITY, INFINITY});
            p.strip_hi.assign(n, {-INFINITY, -INFINITY, -INFINITY});
            for (int i = 0; i < n; ++i)
                for (int ii = i; ii <= i + 1; ++ii)
                    for (int j = 0; j <= n; ++j)
                        for (int a = 0; a < 3; ++a) {
                            p.strip_lo[i][a] =
                                std::min(p.strip_lo[i][a], p.grid[ii * (n + 1) + j][a] - p.delta);
                            p.strip_hi[i][a] =
                                std::max(p.strip_hi[i][a], p.grid[ii * (n + 1) + j][a] + p.delta);
                        }
            m_patches.push_back(std::move(p));
        }
    }

    /// seed-independent bound on |Q(u, v) - L(u, v)|, L the piecewise linear interpolant on the
    /// triangles of an h x h grid. For x in a triangle with vertices x_k and barycentrics l_k,
    /// Taylor's theorem with integral remainder around x gives
    ///   Q(x) - sum l_k Q(x_k) = -sum l_k int_0^1 (1 - s) D2Q(x + s (x_k - x))[x_k - x, x_k - x] ds,
    /// and every offset x_k - x has |du|, |dv| <= h, so
    ///   |Q - L| <= 1/2 h^2 (max|Q_uu| + 2 max|Q_uv| + max|Q_vv|).
    /// The maxima are bounded by the largest control point of each second-derivative net (convex
    /// hull property): Q_uu has the net 6 (P[i+2][j] - 2 P[i+1][j] + P[i][j]), Q_uv the net
    /// 9 (P[i+1][j+1] - P[i+1][j] - P[i][j+1] + P[i][j]), Q_vv likewise along j.
    static double tessellation_bound(const Net& net, double h) {
        auto P = [&](int i, int j) { return v3(net.p[4 * i + j]); };
        double muu = 0, muv = 0, mvv = 0;
        for (int i = 0; i < 2; ++i)
            for (int j = 0; j < 4; ++j)
                muu = std::max(muu, 6 * norm3(add(sub(P(i + 2, j), mul(P(i + 1, j), 2)), P(i, j))));
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 2; ++j)
                mvv = std::max(mvv, 6 * norm3(add(sub(P(i, j + 2), mul(P(i, j + 1), 2)), P(i, j))));
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                muv = std::max(muv,
                               9 * norm3(add(sub(sub(P(i + 1, j + 1), P(i + 1, j)), P(i, j + 1)), P(i, j))));
        return 0.5 * h * h * (muu + 2 * muv + mvv);
    }

    struct Hit {
        double t = INFINITY;
        int patch = -1;
        V3 normal{0, 0, 0};  ///< unit triangle normal
    };

    Hit trace(const V3& o, const V3& d) const {
        Hit best;
        for (std::size_t p = 0; p < m_patches.size(); ++p) {
            const Patch& pt = m_patches[p];
            for (int i = 0; i < m_n; ++i) {
                if (!box_hit(o, d, pt.strip_lo[i], pt.strip_hi[i], best.t)) continue;
                for (int j = 0; j < m_n; ++j) {
                    const V3& a = pt.grid[i * (m_n + 1) + j];
                    const V3& b = pt.grid[(i + 1) * (m_n + 1) + j];
                    const V3& c = pt.grid[(i + 1) * (m_n + 1) + j + 1];
                    const V3& e = pt.grid[i * (m_n + 1) + j + 1];
                    triangle(o, d, a, b, c, int(p), best);
                    triangle(o, d, a, c, e, int(p), best);
                }
            }
        }
        return best;
    }

    double delta(int patch) const { return m_patches[patch].delta; }
    double max_delta() const {
        double m = 0;
        for (const auto& p : m_patches) m = std::max(m, p.delta);
        return m;
    }

private:
    struct Patch {
        std::vector<V3> grid;
        std::vector<V3> strip_lo, strip_hi;
        double delta = 0;
    };

    static bool box_hit(const V3& o, const V3& d, const V3& lo, const V3& hi, double t_max) {
        double t0 = 0, t1 = t_max;
        return prt::bench::clip_to_box(o, d, lo, hi, t0, t1);
    }

    /// Moeller-Trumbore, both faces, t > 0.
    static void triangle(const V3& o, const V3& d, const V3& a, const V3& b, const V3& c, int patch,
                         Hit& best) {
        double t = 0, u = 0, v = 0;
        if (!prt::bench::ray_triangle(o, d, a, b, c, 1e-300, t, u, v)) return;
        if (t > 0 && t < best.t) {
            best.t = t;
            best.patch = patch;
            best.normal = unit3(cross3(sub(b, a), sub(c, a)));
        }
    }

    int m_n;
    std::vector<Patch> m_patches;
};

/// Primary rays of a pinhole camera looking at `centre` from (azimuth, elevation) degrees, z up.
std::vector<std::pair<V3, V3>> camera_rays(const V3& centre, double radius, double az, double el, int size) {
    const double k = 3.14159265358979323846 / 180.0;
    const V3 dir{std::cos(el * k) * std::cos(az * k), std::cos(el * k) * std::sin(az * k), std::sin(el * k)};
    const V3 eye = add(centre, mul(dir, 3.0 * radius));
    const V3 fwd = mul(dir, -1.0);
    const V3 right = unit3(cross3(fwd, {0, 0, 1}));
    const V3 up = cross3(right, fwd);
    const double half = std::tan(20 * k);
    std::vector<std::pair<V3, V3>> rays;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double sx = ((x + 0.5) / size * 2 - 1) * half, sy = (1 - (y + 0.5) / size * 2) * half;
            rays.push_back({eye, unit3(add(fwd, add(mul(right, sx), mul(up, sy))))});
        }
    return rays;
}

const V3 k_centre{0.2, 0.0, 1.575};  // middle of the teapot's box
constexpr double k_radius = 3.6;     // about its bounding sphere

/// Within this parameter distance of a patch's border, the true surface may extend beyond the
/// tessellation's border chord (by up to delta): rays there may hit the patch and miss the mesh.
constexpr double k_border = 0.01;
/// Rays this close to tangent (|cos| between ray and normal) are silhouette rays: there the mesh and
/// the surface can legitimately disagree about hit or miss, and t is ill-conditioned.
constexpr double k_grazing = 0.1;

TEST(Teapot, MatchesFinelyTessellatedReference) {
    REQUIRE_TEAPOT();
    const std::vector<Net> nets = teapot_nets();
    ASSERT_EQ(nets.size(), 32u);
    const BuiltPool bp = build_pool(nets);
    const TriangleReference ref(nets, 48);
    EXPECT_LT(ref.max_delta(), 0.01);  // the reference is within 1/300 of the teapot's size
    for (const auto& [az, el] : std::vector<std::pair<double, double>>{{-60, 25}, {90, 70}, {200, -30}}) {
        int both = 0, disagree = 0;
        for (const auto& [o, d] : camera_rays(k_centre, k_radius, az, el, 96)) {
            const auto r = ref.trace(o, d);
            PatchHit h;
            const bool got = prt::core::trace_patches(bp.view, local_ray(bp, o, d), PatchTraceParams{}, h);
            const bool has_ref = r.patch >= 0;
            if (!got && !has_ref) continue;
            if (got) {
                ASSERT_TRUE(std::isfinite(h.t) && prt::core::is_finite(h.normal));
                EXPECT_NEAR(prt::core::length(h.normal), 1.0, 1e-12);
            }
            const double c_ref = has_ref ? std::fabs(dot3(r.normal, d)) : 1.0;
            const double c_hit = got ? std::fabs(dot3(v3(h.normal), d)) : 1.0;
            // The hit distance bound: the mesh point lies within delta of the surface, so along a
            // ray meeting the surface at angle acos(c) the distances differ by about delta / c.
            if (got && has_ref && std::fabs(h.t - r.t) <= ref.delta(r.patch) / c_ref) {
                ++both;
                continue;
            }
            // Any other outcome must be a silhouette or a patch border (see k_grazing, k_border).
            ++disagree;
            const bool grazing = std::min(c_ref, c_hit) < k_grazing;
            const bool border =
                got && (std::min(h.u, 1 - h.u) < k_border || std::min(h.v, 1 - h.v) < k_border);
            EXPECT_TRUE(grazing || border) << "view " << az << "," << el << ": ref " << (has_ref ? r.t : -1)
                                           << " (cos " << c_ref << "), patches " << (got ? h.t : -1)
                                           << " (cos " << c_hit << ", uv " << h.u << " " << h.v << ")";
        }
        EXPECT_GT(both, 1500) << "view " << az << "," << el;
        EXPECT_LE(disagree, both / 200) << "view " << az << "," << el;
    }
}

/// The early stops of Newton (PatchTraceParams::max_stalled_steps, duplicate_radius) only end runs
/// that would not change the hit: with them off, every ray of three views gets the same hit.
TEST(Teapot, NewtonEarlyStopsKeepEveryHit) {
    REQUIRE_TEAPOT();
    const BuiltPool bp = build_pool(teapot_nets());
    PatchTraceParams off;
    off.max_stalled_steps = 0;
    off.duplicate_radius = 0.0;
    const PatchTraceParams on;
    ASSERT_GT(on.max_stalled_steps, 0u);
    ASSERT_GT(on.duplicate_radius, 0.0);
    for (const auto& [az, el] : std::vector<std::pair<double, double>>{{-60, 25}, {90, 70}, {200, -30}}) {
        int hits = 0;
        prt::core::PatchStats st_on, st_off;
        for (const auto& [o, d] : camera_rays(k_centre, k_radius, az, el, 128)) {
            const auto ray = local_ray(bp, o, d);
            PatchHit a, b;
            const bool got_on = prt::core::trace_patches(bp.view, ray, on, a, &st_on);
            const bool got_off = prt::core::trace_patches(bp.view, ray, off, b, &st_off);
            ASSERT_EQ(got_on, got_off) << "view " << az << "," << el;
            if (!got_on) continue;
            ++hits;
            EXPECT_NEAR(a.t, b.t, 1e-9 * b.t);
            EXPECT_EQ(a.patch, b.patch);
        }
        EXPECT_GT(hits, 2000);
        // and they save Newton steps
        EXPECT_LT(st_on.newton_iterations, st_off.newton_iterations) << "view " << az << "," << el;
    }
}

/// Newton in float (issue 9's float-versus-double trade, PatchPrecision::f32): the same hits as
/// double but for rays at silhouettes and patch borders, within float accuracy of them, and
/// measurably less accurate than double (the float path really is float).
TEST(Teapot, FloatNewtonStaysWithinFloatAccuracy) {
    REQUIRE_TEAPOT();
    const BuiltPool bp = build_pool(teapot_nets());
    const PatchTraceParams params;
    for (const auto& [az, el] : std::vector<std::pair<double, double>>{{-60, 25}, {90, 70}, {200, -30}}) {
        int both = 0, flips = 0;
        double worst = 0.0;
        for (const auto& [o, d] : camera_rays(k_centre, k_radius, az, el, 128)) {
            const auto ray = local_ray(bp, o, d);
            PatchHit a, b;
            const bool got64 = prt::core::trace_patches(bp.view, ray, params, a);
            const bool got32 = prt::core::trace_patches<prt::core::PatchPrecision::f32>(bp.view, ray, params, b);
            if (got32) {
                ASSERT_TRUE(std::isfinite(b.t) && prt::core::is_finite(b.normal));
            }
            if (got64 != got32) {
                ++flips;
                continue;
            }
            if (!got64) continue;
            ++both;
            const double c = std::max(std::fabs(dot3(v3(a.normal), d)), 0.05);
            worst = std::max(worst, std::fabs(a.t - b.t) * c / k_radius);
        }
        std::printf("view %g,%g: %d hits, %d flips, worst |dt| cos / radius %.3g\n", az, el, both, flips, worst);
        EXPECT_GT(both, 2000) << "view " << az << "," << el;
        EXPECT_LE(flips, both / 200) << "view " << az << "," << el;
        EXPECT_LT(worst, 1e-5) << "view " << az << "," << el;
        EXPECT_GT(worst, 1e-9) << "view " << az << "," << el << ": no float rounding seen";
    }
}

TEST(Teapot, SilhouetteSweepHasOneTransitionAndNoNaN) {
    REQUIRE_TEAPOT();
    const BuiltPool bp = build_pool(teapot_nets());
    // Rays along +x at height z = 1.2, offset sideways in y across the body's silhouette (the
    // spout and handle lie near y = 0, so only the body is met).
    auto sweep = [&](double y0, double y1, int steps, double& last_hit_y) {
        int transitions = 0;
        bool previous = true;
        last_hit_y = y0;
        for (int i = 0; i <= steps; ++i) {
            const double y = y0 + (y1 - y0) * i / steps;
            const V3 o{-5, y, 1.2};
            PatchHit h;
            const bool got =
                prt::core::trace_patches(bp.view, local_ray(bp, o, {1, 0, 0}), PatchTraceParams{}, h);
            if (got) {
                EXPECT_TRUE(std::isfinite(h.t) && prt::core::is_finite(h.normal) &&
                            prt::core::is_finite(h.position));
                EXPECT_NEAR(prt::core::length(h.normal), 1.0, 1e-12);
                // the hit lies on the ray and on the patch at the reported (u, v)
                const auto e = prt::core::patch_eval(bp.view.nets[h.patch], h.u, h.v);
                const V3 on_ray =
                    sub(add(o, mul(V3{1, 0, 0}, h.t)), {bp.origin[0], bp.origin[1], bp.origin[2]});
                EXPECT_LT(norm3(sub(v3(e.q), on_ray)), 1e-9);
                last_hit_y = y;
            }
            if (got != previous) ++transitions;
            previous = got;
        }
        return transitions;
    };
    double y_star = 0;
    EXPECT_EQ(sweep(1.5, 2.5, 4000, y_star), 1);
    EXPECT_GT(y_star, 1.6);
    double y_fine = 0;
    EXPECT_EQ(sweep(y_star - 1e-3, y_star + 1e-3, 2000, y_fine), 1);
    double y_finer = 0;
    EXPECT_EQ(sweep(y_fine - 1e-6, y_fine + 1e-6, 1000, y_finer), 1);
}

/// A point where whole patch edges collapsed (the lid's top, the bottom's centre), with the
/// (patch, edge) pairs that meet there; edges: 0 u = 0, 1 u = 1, 2 v = 0, 3 v = 1.
struct Apex {
    V3 point;
    std::vector<std::pair<int, int>> edges;
};

std::vector<Apex> collapsed_points(const std::vector<Net>& nets) {
    std::vector<Apex> apexes;
    const int edges[4][4] = {{0, 1, 2, 3}, {12, 13, 14, 15}, {0, 4, 8, 12}, {3, 7, 11, 15}};
    for (std::size_t n = 0; n < nets.size(); ++n)
        for (int e = 0; e < 4; ++e) {
            const V3 p = v3(nets[n].p[edges[e][0]]);
            bool same = true;
            for (int k = 1; k < 4; ++k) same = same && norm3(sub(v3(nets[n].p[edges[e][k]]), p)) == 0.0;
            if (!same) continue;
            auto it = std::find_if(apexes.begin(), apexes.end(),
                                   [&](const Apex& a) { return norm3(sub(p, a.point)) == 0.0; });
            if (it == apexes.end()) it = apexes.insert(apexes.end(), Apex{p, {}});
            it->edges.push_back({int(n), e});
        }
    return apexes;
}

/// Rays per collapsed point (PRT_CORNER_RAYS raises it for a stress run: 200000 passed).
const int k_corner_rays = std::getenv("PRT_CORNER_RAYS") ? std::atoi(std::getenv("PRT_CORNER_RAYS")) : 3000;

TEST(Teapot, RaysAtDegenerateCornersHitWithFiniteNormalsOrMiss) {
    REQUIRE_TEAPOT();
    const std::vector<Net> nets = teapot_nets();
    const std::vector<Apex> apexes = collapsed_points(nets);
    ASSERT_EQ(apexes.size(), 2u);  // lid top (0, 0, 3.15) and bottom centre (0, 0, 0)
    const BuiltPool bp = build_pool(nets);
    std::mt19937_64 rng(14);
    std::normal_distribution<double> g;
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    int direct = 0;
    for (const Apex& apex : apexes) {
        EXPECT_EQ(apex.edges.size(), 4u);                         // four patches meet at each
        const double outward = apex.point[2] > 1.5 ? 1.0 : -1.0;  // +z above the lid, -z below the bottom
        for (int i = 0; i < k_corner_rays; ++i) {
            const V3 w = unit3({g(rng), g(rng), g(rng)});
            // Targets on the surface: the apex itself, and points at parameter distance s from the
            // collapsed edge of one of its patches (about s times the patch size from the apex).
            static constexpr double k_distance[5] = {0.0, 1e-9, 1e-7, 1e-5, 1e-3};
            const double s = k_distance[i % 5];
            const auto [n, e] = apex.edges[std::size_t(uni(rng) * apex.edges.size()) % apex.edges.size()];
            const double along = uni(rng);
            const double u = e == 0 ? s : (e == 1 ? 1 - s : along), v = e == 2 ? s : (e == 3 ? 1 - s : along);
            const V3 target = matrix_eval(nets[n], u, v).q;
            const V3 o = add(target, mul(w, 5.0));
            PatchHit h;
            const bool got =
                prt::core::trace_patches(bp.view, local_ray(bp, o, mul(w, -1.0)), PatchTraceParams{}, h);
            if (got) {
                ASSERT_TRUE(std::isfinite(h.t) && prt::core::is_finite(h.normal)) << i;
                EXPECT_NEAR(prt::core::length(h.normal), 1.0, 1e-12);
                // The target is on the surface, so no hit lies beyond it, except for rays nearly
                // tangent there (the normal is about +-z): grazing is ill-conditioned.
                if (std::fabs(w[2]) > k_grazing) {
                    EXPECT_LE(h.t, 5.0 + 1e-6) << "apex z " << apex.point[2] << " w " << w[0] << "," << w[1]
                                               << "," << w[2] << " s " << s;
                }
            }
            // Seen straight on (the tip of the lid's knob from above, the bottom from below), the
            // ray must hit the target itself, with the surface-of-revolution normal +-z.
            if (w[2] * outward > 0.5) {
                ++direct;
                ASSERT_TRUE(got) << "missed near the collapsed point " << apex.point[2] << " from " << w[0]
                                 << "," << w[1] << "," << w[2] << " s " << s;
                EXPECT_NEAR(h.t, 5.0, 1e-6);
                EXPECT_GT(std::fabs(h.normal.z), 0.99);
            }
        }
    }
    EXPECT_GT(direct, 50);
}

TEST(Teapot, OrientationMakesVisibleSurfacesFrontFacing) {
    REQUIRE_TEAPOT();
    const std::vector<Net> nets = teapot_nets();
    const BuiltPool oriented = build_pool(nets, 6, true);
    const BuiltPool raw = build_pool(nets, 6, false);
    EXPECT_TRUE(oriented.view.flags & prt::pool::k_patch_oriented);
    EXPECT_FALSE(raw.view.flags & prt::pool::k_patch_oriented);
    int hits = 0, front_oriented = 0, front_raw = 0;
    for (const auto& [o, d] : camera_rays(k_centre, k_radius, 30, 20, 64)) {
        PatchHit a, b;
        const bool ga =
            prt::core::trace_patches(oriented.view, local_ray(oriented, o, d), PatchTraceParams{}, a);
        const bool gb = prt::core::trace_patches(raw.view, local_ray(raw, o, d), PatchTraceParams{}, b);
        ASSERT_EQ(ga, gb);  // orientation does not change the surface
        if (!ga) continue;
        EXPECT_NEAR(a.t, b.t, 1e-9);
        ++hits;
        front_oriented += a.front;
        front_raw += b.front;
    }
    ASSERT_GT(hits, 500);
    // From outside one sees the outer surface, except through the gap under the lid's rim.
    EXPECT_GT(front_oriented, hits * 95 / 100);
    // The file's own u/v order points every patch's dQ/du x dQ/dv inwards.
    EXPECT_LT(front_raw, hits * 5 / 100);
}

TEST(Teapot, BackFaceCullingNeverRemovesAFrontFace) {
    REQUIRE_TEAPOT();
    const BuiltPool bp = build_pool(teapot_nets(), 6, true);
    const auto& view = bp.view;
    PatchTraceParams front;
    front.faces = prt::core::k_patch_faces_by_ray;
    for (const auto& [az, el] : std::vector<std::pair<double, double>>{{-60, 25}, {120, 5}, {10, -40}}) {
        const auto rays = camera_rays(k_centre, k_radius, az, el, 64);
        const V3 eye_world = rays[0].first;
        const auto eye = local_ray(bp, eye_world, {1, 0, 0}).origin;
        std::vector<std::uint32_t> node_words(std::size_t(view.patch_count) *
                                              prt::core::patch_cull_words(view));
        std::vector<std::uint32_t> bvh_words(prt::core::bvh_cull_words(view));
        for (std::uint32_t p = 0; p < view.patch_count; ++p)
            prt::core::mark_backfacing_patch(view, p, eye, node_words.data());
        prt::core::mark_backfacing_bvh(view, node_words.data(), bvh_words.data());
        const prt::core::PatchCullMask mask{node_words.data(), bvh_words.data()};
        std::size_t culled = 0;
        for (std::uint32_t p = 0; p < view.patch_count; ++p)
            for (std::uint32_t k = 0; k < view.subpatch_nodes; ++k)
                culled += prt::core::cull_bit(node_words.data(),
                                              std::size_t(p) * prt::core::patch_cull_words(view) * 32 + k);
        EXPECT_GT(culled, std::size_t(view.patch_count) * view.subpatch_nodes / 4) << "culling does nothing";
        std::uint64_t boxes_plain = 0, boxes_culled = 0;
        for (const auto& [o, d] : rays) {
            PatchHit a, b;
            prt::core::PatchStats sa, sb;
            const bool ga = prt::core::trace_patches(view, local_ray(bp, o, d), front, a, &sa);
            const bool gb = prt::core::trace_patches(view, local_ray(bp, o, d), front, b, &sb, &mask);
            ASSERT_EQ(ga, gb);
            if (ga) {
                EXPECT_EQ(a.t, b.t);
            }
            boxes_plain += sa.subpatch_boxes + sa.bvh_nodes;
            boxes_culled += sb.subpatch_boxes + sb.bvh_nodes;
        }
        EXPECT_LT(boxes_culled, boxes_plain);
    }
}

}  // namespace
