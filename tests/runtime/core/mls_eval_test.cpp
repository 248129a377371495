// F through the kd-tree (core mls_eval, float and double sums) against WS05 eq. 2 evaluated by
// brute force over every splat in double precision; and the measured float error of the two
// algebraically equal forms of eq. 2.
#include <gtest/gtest.h>

#include <cstdio>

#include "mls_test_util.h"

namespace {

using namespace prt;
using namespace prt::mls_test;

/// Random points in the band |x| in [R - 2h, R + 2h] around a sphere of radius R.
std::vector<D3> band_points(std::size_t n, double radius, double band, const D3& c, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0.0, 1.0);
    std::uniform_real_distribution<double> u(-band, band);
    std::vector<D3> out;
    for (std::size_t i = 0; i < n; ++i) {
        D3 v{g(rng), g(rng), g(rng)};
        const double l = norm3(v);
        const double r = radius + u(rng);
        out.push_back({c[0] + v[0] / l * r, c[1] + v[1] / l * r, c[2] + v[2] / l * r});
    }
    return out;
}

TEST(MlsEval, SignAndValueAgreeWithDoublePrecisionBruteForce) {
    const PointSet s = fibonacci_sphere(3000);
    // Without shrinking every leaf holds every splat reaching it, so F through the tree is F
    // everywhere (shrinking empties cells proven free of zeros: there mls_eval returns 0).
    mls::BuildOptions opt;
    opt.support_factor = 1.0f;  // supports of one radius: the sample counts below assume them
    opt.shrink = false;
    const mls::MlsModel m = build(s, opt);
    const core::MlsView view = mls::make_view(m);
    mls::BuildOptions shrinking;
    shrinking.support_factor = 1.0f;
    const mls::MlsModel shrunk = build(s, shrinking);
    const core::MlsView shrunk_view = mls::make_view(shrunk);
    const double h = s.radii[0];
    std::size_t checked = 0, decided = 0, in_filled = 0;
    for (const D3& x : band_points(3000, 1.0, 1.5 * h, {0, 0, 0}, 7)) {
        const core::Vec3 xf{float(x[0]), float(x[1]), float(x[2])};
        const D3 xs = d3(xf);  // the point the core sees
        const BruteF ref = brute_f(m.splats, xs);
        const core::MlsSums<double> sd = core::mls_eval<double>(view, xf);
        const core::MlsSums<float> sf = core::mls_eval<float>(view, xf);
        // The shrunk tree: the same F wherever its leaf is not empty.
        const std::uint32_t leaf = core::mls_locate_leaf(shrunk_view, xf);
        if (leaf == shrunk_view.node_count) {  // outside the root cell: no support reaches x
            EXPECT_EQ(ref.w, 0.0);
        } else if (pool::mls_leaf_count(shrunk.nodes[leaf]) > 0) {
            ++in_filled;
            const core::MlsSums<double> ss = core::mls_eval<double>(shrunk_view, xf);
            EXPECT_NEAR(ss.w, ref.w, 1e-9 * (1.0 + ref.w));
            EXPECT_NEAR(ss.f(), ref.f, 1e-9 * (ref.w * ref.w * h + 1e-30));
        }
        // The leaf holds every splat reaching x: same W as the sum over all splats.
        ASSERT_NEAR(sd.w, ref.w, 1e-9 * (1.0 + ref.w));
        // |F| scale: W^2 h (W up to ~10, |x - p| up to h); float weights 1 - sqrt(q) carry an
        // absolute error ~1e-7 each, so near the support boundary (W << 1) the float error is
        // absolute, not relative to W^2: scale (1 + W)^2 h.
        const double scale = (1.0 + ref.w) * (1.0 + ref.w) * h;
        EXPECT_NEAR(sd.f(), ref.f, 1e-9 * scale);
        EXPECT_NEAR(double(sf.f()), ref.f, 1e-6 * scale);
        ++checked;
        if (std::abs(ref.f) > 1e-5 * scale) {
            ++decided;
            EXPECT_EQ(sf.f() > 0, ref.f > 0)
                << "float F has the wrong sign at " << x[0] << "," << x[1] << "," << x[2];
            EXPECT_EQ(sd.f() > 0, ref.f > 0);
        }
    }
    EXPECT_EQ(checked, 3000u);
    EXPECT_GT(decided, 1500u);  // the rest: W = 0 (beyond every support) or F within float noise of 0
    EXPECT_GT(in_filled, 1000u);
}

TEST(MlsEval, ZeroOutsideTheSupportAndOutsideTheRoot) {
    const PointSet s = fibonacci_sphere(500);
    const mls::MlsModel m = build(s);
    const core::MlsView view = mls::make_view(m);
    const core::MlsSums<float> centre = core::mls_eval<float>(view, core::Vec3{0, 0, 0});
    EXPECT_EQ(centre.w, 0.0f);  // the sphere's centre is far from every splat
    EXPECT_EQ(centre.f(), 0.0f);
    const core::MlsSums<float> far = core::mls_eval<float>(view, core::Vec3{10, 0, 0});
    EXPECT_EQ(far.w, 0.0f);
    EXPECT_EQ(core::mls_locate_leaf(view, core::Vec3{10, 0, 0}), view.node_count);
}

/// The float error of eq. 2 written as WS05 does, (W x - sum w p) . N, against the form the core
/// uses, (sum w (x - p)) . N, on a model far from the local origin's scale: a sphere of radius 1
/// sampled densely enough that |x| / h ~ 150. Both against double brute force. Measured, printed,
/// and the core's form must be the better one.
TEST(MlsEval, FloatErrorOfTheTwoFormsMeasured) {
    const PointSet s = fibonacci_sphere(200000, 1.0, {0, 0, 0});
    // Points near one spot only: brute force stays cheap with a local candidate list.
    std::vector<pool::MlsSplat> local;
    const D3 spot{0.6, 0.64, 0.48};
    for (std::size_t i = 0; i < s.positions.size(); ++i) {
        const D3 p = d3(s.positions[i]);
        if (norm3(D3{p[0] - spot[0], p[1] - spot[1], p[2] - spot[2]}) < 0.05)
            local.push_back({s.positions[i], 1.0f / s.radii[i], s.normals[i], std::uint32_t(i)});
    }
    ASSERT_GT(local.size(), 100u);
    const double h = s.radii[0];
    double err_core = 0, err_paper = 0, scale_sum = 0;
    std::size_t n = 0;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int i = 0; i < 400; ++i) {
        D3 v{spot[0] + 0.015 * u(rng), spot[1] + 0.015 * u(rng), spot[2] + 0.015 * u(rng)};
        const double r = (1.0 + h * u(rng)) / norm3(v);
        const D3 x{v[0] * r, v[1] * r, v[2] * r};
        const core::Vec3 xf{float(x[0]), float(x[1]), float(x[2])};
        const BruteF ref = brute_f(local, d3(xf));
        if (!(ref.w > 0)) continue;
        // Core form in float.
        float w = 0, ax = 0, ay = 0, az = 0, nx = 0, ny = 0, nz = 0;
        // Paper form in float.
        float px = 0, py = 0, pz = 0;
        for (const pool::MlsSplat& sp : local) {
            const float dx = xf.x - sp.position.x, dy = xf.y - sp.position.y, dz = xf.z - sp.position.z;
            const float q = (dx * dx + dy * dy + dz * dz) * sp.inv_support * sp.inv_support;
            if (!(q < 1.0f)) continue;
            const float wi = 1.0f - std::sqrt(q);
            w += wi;
            ax += wi * dx;
            ay += wi * dy;
            az += wi * dz;
            px += wi * sp.position.x;
            py += wi * sp.position.y;
            pz += wi * sp.position.z;
            nx += wi * sp.normal.x;
            ny += wi * sp.normal.y;
            nz += wi * sp.normal.z;
        }
        const double f_core = double(ax * nx + ay * ny + az * nz);
        const double f_paper = double((w * xf.x - px) * nx + (w * xf.y - py) * ny + (w * xf.z - pz) * nz);
        const double scale = ref.w * ref.w * h;
        err_core += std::abs(f_core - ref.f) / scale;
        err_paper += std::abs(f_paper - ref.f) / scale;
        scale_sum += scale;
        ++n;
    }
    ASSERT_GT(n, 20u);
    err_core /= double(n);
    err_paper /= double(n);
    std::printf(
        "[ measured ] float F error relative to W^2 h (|x|/h = %.0f): core form %.2e, WS05 form %.2e\n",
        1.0 / h, err_core, err_paper);
    RecordProperty("float_error_core_form", std::to_string(err_core));
    RecordProperty("float_error_ws05_form", std::to_string(err_paper));
    EXPECT_LT(err_core, 1e-5);
    EXPECT_LT(err_core, err_paper);
}

}  // namespace
