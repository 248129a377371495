// prt-iso's corner values against a direct evaluation of thesis eq. 4.1-4.3 in double precision
// over every point (iso_test_util.h): isovalues, normals and colors, float and quantized leaves,
// radii of influence from k-NN (checked against brute force) and from a radii section, smoothing,
// and corners no point's support reaches (against the untruncated Gaussian).
#include <gtest/gtest.h>

#include <cmath>

#include "iso_test_util.h"

namespace {

using namespace prt;
using namespace prt::iso_test;

struct CornerCheck {
    std::size_t checked = 0, far = 0;
    double max_f_error = 0, max_q8_error_in_steps = 0, max_normal_deg = 0, max_color_error = 0;
};

/// Compares every corner of every leaf of `model` with the reference built from `sigma`.
CornerCheck check_corners(const iso::IsoModel& model, const PointSet& s, const std::vector<double>& sigma,
                          double support, bool colors) {
    CornerCheck r;
    const auto cells = iso::leaf_cells(model.nodes, model.info.leaf_count);
    for (std::size_t l = 0; l < cells.size(); ++l) {
        const double edge = std::ldexp(double(model.info.root_size), -int(cells[l].level));
        for (int c = 0; c < 8; ++c) {
            D3 q;
            iso::corner_position(model.info, cells[l], c, q.data());
            const Reference ref = reference_truncated(s, sigma, support, q);
            if (ref.counted == 0) {
                ++r.far;
                continue;
            }
            ++r.checked;
            const pool::IsoLeafF32& f = model.leaves_f32[l];
            r.max_f_error = std::max(r.max_f_error, std::abs(double(f.value[c]) - ref.f));
            r.max_normal_deg = std::max(r.max_normal_deg,
                                        angle_deg(D3{f.normal[c][0], f.normal[c][1], f.normal[c][2]}, ref.n));
            if (colors) {
                const double ce =
                    std::max({std::abs(f.color[c].r - ref.color[0]), std::abs(f.color[c].g - ref.color[1]),
                              std::abs(f.color[c].b - ref.color[2])});
                r.max_color_error = std::max(r.max_color_error, ce);
            } else {
                EXPECT_EQ(f.color[c].r, 255);
            }
            // Quantized: sign-preserving rounding of f / (2 edges) to 1/127 steps, clamped.
            const pool::IsoLeafQ8& q8 = model.leaves_q8[l];
            const double step = pool::k_iso_q8_range * edge / 127.0;
            const double clamped =
                std::clamp(ref.f, -pool::k_iso_q8_range * edge, pool::k_iso_q8_range * edge);
            // Rounded to the nearest step, except that a positive value below half a step becomes 1,
            // not 0 (the sign is kept): there the error is up to one step.
            const double q8_error = std::abs(q8.value[c] * step - clamped) / step;
            if (std::abs(clamped) > step) {
                r.max_q8_error_in_steps = std::max(r.max_q8_error_in_steps, q8_error);
            } else {
                EXPECT_LE(q8_error, 1.0 + 1e-6);
            }
            if (ref.f > 1e-9 * edge) {
                EXPECT_GE(q8.value[c], 1) << "leaf " << l << " corner " << c;
            }
            if (ref.f < -1e-9 * edge) {
                EXPECT_LE(q8.value[c], 0) << "leaf " << l << " corner " << c;
            }
            for (int a = 0; a < 3; ++a) EXPECT_NEAR(q8.normal[c][a] / 127.0, ref.n[a], 0.5 / 127 + 1e-6);
        }
    }
    return r;
}

TEST(IsoEval, CornersMatchEquations41To43WithKnnRadii) {
    const PointSet s = synth_points(sphere_shape(1.0), 3000, 0.002, true);
    iso::BuildOptions o;
    o.max_level = 6;
    o.storage = iso::Storage::both;
    o.drop_uncrossed = false;
    o.smoothing = 1.0f;  // the thesis's sigma = r: every corner of this level within a support
    o.one_side = false;  // eq. 4.1-4.3 as written
    o.threads = 2;
    const iso::IsoModel model = iso::build_iso(s.input(), o);
    const std::vector<double> radii = brute_knn_radii(s, o.knn, o.knn_clamp);
    std::vector<double> sorted(radii);
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    EXPECT_NEAR(model.stats.radius_median, sorted[sorted.size() / 2], 1e-12);
    EXPECT_TRUE(model.info.flags & pool::k_iso_radii_knn);
    EXPECT_TRUE(model.info.flags & pool::k_iso_colors);
    std::vector<double> sigma(radii);
    for (double& v : sigma) v *= o.smoothing;
    const CornerCheck r = check_corners(model, s, sigma, o.support, true);
    EXPECT_GT(r.checked, 20000u);
    EXPECT_EQ(r.far, 0u);
    EXPECT_LT(r.max_f_error, 1e-6);  // float storage of values up to ~0.1
    EXPECT_LT(r.max_normal_deg, 1e-3);
    EXPECT_LE(r.max_color_error, 0.5 + 1e-9);  // rounded to bytes
    EXPECT_LE(r.max_q8_error_in_steps, 0.5 + 1e-6);
    std::printf("knn: %zu corners, max |f - ref| %.3g, normal %.3g deg, q8 %.3f steps\n", r.checked,
                r.max_f_error, r.max_normal_deg, r.max_q8_error_in_steps);
}

TEST(IsoEval, CornersMatchWithRadiiSectionSmoothingAndSupport) {
    PointSet s = synth_points(torus_shape(1.0, 0.35), 4000, 0.0, false);
    std::vector<double> radii(s.positions.size());
    for (std::size_t i = 0; i < radii.size(); ++i) {
        radii[i] = 0.06 * (1.0 + 0.5 * std::sin(0.37 * double(i)));  // varied radii: several size classes
        s.radii.push_back(float(radii[i]));
    }
    iso::BuildOptions o;
    o.max_level = 6;
    o.smoothing = 0.7f;
    o.support = 2.5f;
    o.storage = iso::Storage::both;
    o.drop_uncrossed = false;
    o.threads = 2;
    const iso::IsoModel model = iso::build_iso(s.input(true), o);
    EXPECT_FALSE(model.info.flags & pool::k_iso_radii_knn);
    EXPECT_FALSE(model.info.flags & pool::k_iso_colors);
    std::vector<double> sigma(s.radii.begin(), s.radii.end());
    for (double& v : sigma) v *= double(o.smoothing);
    const CornerCheck r = check_corners(model, s, sigma, o.support, false);
    EXPECT_GT(r.checked, 10000u);
    EXPECT_LT(r.max_f_error, 1e-6);
    EXPECT_LT(r.max_normal_deg, 1e-3);
    EXPECT_LE(r.max_q8_error_in_steps, 0.5 + 1e-6);
}

TEST(IsoEval, FarCornersMatchTheUntruncatedGaussian) {
    // Level 2 of a sphere of 2000 points: leaves half the radius wide, most corners beyond every
    // point's support (thesis 4.6: a coarse level of detail).
    const PointSet s = synth_points(sphere_shape(1.0), 2000);
    iso::BuildOptions o;
    o.min_level = 2;
    o.max_level = 2;
    o.storage = iso::Storage::f32;
    o.drop_uncrossed = false;
    o.one_side = false;  // the untruncated eq. 4.1-4.3 over every point
    o.smoothing = 1.0f;  // the reference's sigma = r
    o.threads = 2;
    const iso::IsoModel model = iso::build_iso(s.input(), o);
    EXPECT_GT(model.stats.far_corners, 10u);
    const std::vector<double> radii = brute_knn_radii(s, o.knn, o.knn_clamp);
    const auto cells = iso::leaf_cells(model.nodes, model.info.leaf_count);
    std::size_t far = 0;
    double worst = 0;
    for (std::size_t l = 0; l < cells.size(); ++l)
        for (int c = 0; c < 8; ++c) {
            D3 q;
            iso::corner_position(model.info, cells[l], c, q.data());
            if (reference_truncated(s, radii, o.support, q).counted > 0) continue;
            ++far;
            const Reference ref = reference_full(s, radii, q);
            const double f = model.leaves_f32[l].value[c];
            worst = std::max(worst, std::abs(f - ref.f));
            // A sphere: f has the sign of the true signed distance far from it.
            const double sd = norm3(q) - 1.0;
            if (std::abs(sd) > 0.05) {
                EXPECT_EQ(f > 0, sd > 0) << "corner at distance " << sd;
            }
        }
    EXPECT_GT(far, 10u);
    EXPECT_LT(worst, 1e-6);
    std::printf("far corners: %zu, max |f - untruncated| %.3g\n", far, worst);
}

TEST(IsoEval, OptionsAreValidated) {
    iso::BuildOptions o;
    o.max_level = pool::k_max_iso_level + 1;
    EXPECT_THROW(iso::validate(o), Error);
    o = {};
    o.min_level = 5, o.max_level = 4;
    EXPECT_THROW(iso::validate(o), Error);
    o = {};
    o.smoothing = 0;
    EXPECT_THROW(iso::validate(o), Error);
    o = {};
    o.support = 0.5f;
    EXPECT_THROW(iso::validate(o), Error);
    const PointSet s = synth_points(sphere_shape(), 100);
    iso::BuildInput in = s.input();
    in.normals = {};
    EXPECT_THROW(iso::build_iso(in, iso::BuildOptions{}), Error);
    iso::BuildOptions radii_only;
    radii_only.radius = iso::RadiusSource::radii;
    EXPECT_THROW(iso::build_iso(s.input(), radii_only), Error);  // no radii given
}

}  // namespace
