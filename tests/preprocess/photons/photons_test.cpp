// Tests of prt-photons (thesis 5.4): emission (solid angles, isotropy), power accounting against an
// analytic sphere, a ball lens's focus against paraxial optics, the caustic octree's density
// estimate against a known irradiance, RGB9E5, and the validating loader.
#include "photons.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "gi_frame.h"
#include "gi_test_util.h"
#include "prt/core/gi.h"
#include "prt/runtime/gi_pool.h"
#include "runtime/surface_fixtures.h"

using namespace prt;

namespace {

constexpr double k_pi = 3.14159265358979323846;

double lum(const double c[3]) {
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
}

}  // namespace

TEST(Photons, EmissionCoversTheSphereEvenly) {
    // Every photon of one light: total solid angle 4 pi, and the power inside a cone about a cube
    // diagonal (where equal powers per pixel would be 5x too bright) is the cone's share.
    photons::ShootParams p;
    p.face_res = 64;
    p.per_pixel = 3;
    p.solid_angle_norm = photons::solid_angle_norm(p.face_res);
    const core::Vec3 axis = core::normalize(core::Vec3{1, 1, 1});
    const double cos_cone = std::cos(20.0 * k_pi / 180.0);
    double total = 0, in_cone = 0, upper = 0;
    for (std::uint64_t i = 0; i < photons::photons_per_light(p); ++i) {
        core::Vec3 d;
        float w;
        photons::emit_photon(p, 0, i, d, w);
        ASSERT_NEAR(core::length(d), 1.0f, 1e-5f);
        total += w;
        if (core::dot(d, axis) > cos_cone) in_cone += w;
        if (d.y > 0) upper += w;
    }
    EXPECT_NEAR(total, 4 * k_pi, 4 * k_pi * 1e-5);
    EXPECT_NEAR(upper / total, 0.5, 1e-3);
    EXPECT_NEAR(in_cone / total, (1 - cos_cone) / 2, 0.02 * (1 - cos_cone) / 2);
}

TEST(Photons, PowerIsConservedAndMatchesTheSphereSolidAngle) {
    // A partly mirroring sphere (d 0.3, kr 0.6, absorbs 0.1) seen from a light along a cube diagonal.
    const double R = 0.5;
    test::TestModel m = test::make_model(test::sphere_points({0, 0, 0}, R, 60000), {0, 0, 0});
    const auto pool = test::make_pool(m);
    const rt::RenderScene rs = test::load_gi_scene(R"({
        "lights": [{"type": "point", "position": [1.7320508, 1.7320508, 1.7320508], "color": [1, 0.5, 0.25]}],
        "materials": [{"name": "m", "diffuse_reflectance": 0.3, "reflectivity": 0.6, "use_point_colors": false}],
        "models": [{"name": "s", "pool": "unused.pool"}]})",
                                                   {pool});
    photons::ShootOptions o;
    o.params.face_res = 128;
    o.params.per_pixel = 4;
    o.backend = "cpu";
    const photons::ShootResult r = photons::shoot_photons(rs.view(), o);
    const photons::PhotonTally& t = r.tally;
    for (int a = 0; a < 3; ++a) {
        const double sum = t.direct[a] + t.deposited[a] + t.absorbed[a] + t.escaped[a] + t.truncated[a];
        EXPECT_NEAR(sum, t.emitted[a], 1e-5 * t.emitted[a]) << "channel " << a;
    }
    const double color[3] = {1, 0.5, 0.25};
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(t.emitted[a], 4 * k_pi * color[a], 4 * k_pi * color[a] * 1e-4);
    // A convex mirror cannot send light back to itself: no L S+ D deposits at all.
    EXPECT_EQ(t.deposits, 0u);
    EXPECT_EQ(lum(t.deposited), 0.0);
    // First-hit power H: direct = 0.3 H, absorbed = 0.1 H.
    const double H = lum(t.direct) / 0.3;
    EXPECT_NEAR(lum(t.absorbed), 0.1 * H, 1e-4 * H);
    // H / emitted is the sphere's solid-angle share (1 - cos theta) / 2, sin theta = R / D, for the
    // splat surface between the sphere and the sphere grown by the largest splat radius.
    const double D = 3.0, r_max = m.radii.empty() ? 0 : *std::max_element(m.radii.begin(), m.radii.end());
    auto share = [&](double radius) { return (1 - std::sqrt(1 - radius * radius / (D * D))) / 2; };
    const double f = H / lum(t.emitted);
    EXPECT_GT(f, share(R) * 0.98);
    EXPECT_LT(f, share(R + r_max) * 1.02);
}

namespace {

/// Irradiance at a point on the plane y = 0 from a Lambertian emitter of radiance 1 on the
/// rectangle [x0, x1] x [z0, z1] at height h facing down (parallel planes), in closed form: pi x
/// the form factor from a differential area to a parallel rectangle with a corner above it
/// (Howell's catalogue of configuration factors, C-11: F = 1 / (2 pi) [A / sqrt(1 + A^2)
/// atan(B / sqrt(1 + A^2)) + B / sqrt(1 + B^2) atan(A / sqrt(1 + B^2))], A = a / h, B = b / h),
/// summed with signs over the four rectangles from the foot of the point to the corners.
double parallel_rect_irradiance(double px, double pz, double h, double x0, double x1, double z0, double z1) {
    auto corner = [&](double X, double Y) {  // signed rectangle [0, X] x [0, Y] from the foot
        const double A = std::fabs(X) / h, B = std::fabs(Y) / h;
        const double a1 = std::sqrt(1 + A * A), b1 = std::sqrt(1 + B * B);
        const double F = (A / a1 * std::atan(B / a1) + B / b1 * std::atan(A / b1)) / (2 * k_pi);
        return (X < 0) != (Y < 0) ? -F : F;
    };
    const double F = corner(x1 - px, z1 - pz) - corner(x0 - px, z1 - pz) - corner(x1 - px, z0 - pz) +
                     corner(x0 - px, z0 - pz);
    return k_pi * F;
}

/// The same irradiance by midpoint quadrature of L cos cos' / r^2 over the emitter (L = 1).
double parallel_rect_irradiance_quadrature(double px, double pz, double h, double x0, double x1, double z0,
                                           double z1, int n) {
    double sum = 0;
    const double dx = (x1 - x0) / n, dz = (z1 - z0) / n;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double x = x0 + (i + 0.5) * dx - px, z = z0 + (j + 0.5) * dz - pz;
            const double r2 = x * x + z * z + h * h;
            sum += h * h / (r2 * r2) * dx * dz;
        }
    return sum;
}

}  // namespace

TEST(Photons, AreaLightPhotonsMatchTheAnalyticIrradianceOfASquareLambertianEmitter) {
    // A unit square light of color I at height h = 1 facing down (edge_u x edge_v = -y): its photons
    // (emitted analytically onto the plane y = 0) binned in 0.25 x 0.25 squares over [-2, 2]^2 must
    // give the irradiance of a Lambertian emitter of power pi I, radiance L = I / A, each bin's mean
    // within 4.5 standard deviations of its photon count (equal-power photons: relative sd
    // 1 / sqrt(expected count)), and the bins' chi-square per bin below 1.5.
    const double h = 1.0, side = 1.0;
    const double closed = parallel_rect_irradiance(0.3, -0.7, h, -0.5, 0.5, -0.5, 0.5);
    ASSERT_NEAR(closed, parallel_rect_irradiance_quadrature(0.3, -0.7, h, -0.5, 0.5, -0.5, 0.5, 400),
                1e-4 * closed)
        << "the closed form and the quadrature disagree";
    core::AreaLight a;
    a.corner = core::Vec3{-0.5f, float(h), -0.5f};
    a.edge_u = core::Vec3{float(side), 0, 0};
    a.edge_v = core::Vec3{0, 0, float(side)};
    const double I = 2.0;
    a.color = core::Vec3{float(I), float(I), float(I)};
    photons::ShootParams p;
    p.face_res = 64;
    p.per_pixel = 16;  // 393k photons
    const std::uint64_t n = photons::photons_per_light(p);
    constexpr int k_bins = 16;
    const double lo = -2.0, bin = 0.25;
    std::vector<double> power(k_bins * k_bins, 0.0);
    double total = 0, below = 0;
    for (std::uint64_t i = 0; i < n; ++i) {
        core::Vec3 o, d;
        float share;
        core::emit_area_photon(p, a, 3, i, o, d, share);
        ASSERT_NEAR(core::length(d), 1.0f, 1e-5f);
        ASSERT_GE(o.x, -0.5f);
        ASSERT_LE(o.x, 0.5f);
        ASSERT_FLOAT_EQ(o.y, float(h));
        ASSERT_LT(d.y, 0.0f) << "a photon left the light's back";
        const double flux = share * I;
        total += flux;
        const double t = -o.y / d.y;
        const double x = o.x + t * d.x, z = o.z + t * d.z;
        const int bx = int(std::floor((x - lo) / bin)), bz = int(std::floor((z - lo) / bin));
        if (bx < 0 || bz < 0 || bx >= k_bins || bz >= k_bins) continue;
        power[bz * k_bins + bx] += flux;
        below += flux;
    }
    EXPECT_NEAR(total, k_pi * I, 1e-4 * k_pi * I) << "power: pi I";
    const double L = I / (side * side);
    double chi2 = 0, expected_below = 0;
    for (int bz = 0; bz < k_bins; ++bz)
        for (int bx = 0; bx < k_bins; ++bx) {
            // The bin's mean irradiance: the closed form at 8 x 8 points of the bin.
            double e = 0;
            for (int i = 0; i < 8; ++i)
                for (int j = 0; j < 8; ++j)
                    e += parallel_rect_irradiance(lo + (bx + (i + 0.5) / 8) * bin,
                                                  lo + (bz + (j + 0.5) / 8) * bin, h, -0.5, 0.5, -0.5, 0.5) /
                         64;
            e *= L;
            const double expected_power = e * bin * bin;
            expected_below += expected_power;
            const double expected_count = expected_power / (k_pi * I / double(n));
            const double sd = expected_power / std::sqrt(expected_count);
            const double z = (power[bz * k_bins + bx] - expected_power) / sd;
            chi2 += z * z;
            EXPECT_LT(std::fabs(z), 4.5) << "bin (" << bx << ", " << bz << "): measured "
                                         << power[bz * k_bins + bx] / (bin * bin) << ", analytic " << e;
        }
    EXPECT_LT(chi2 / (k_bins * k_bins), 1.5);
    EXPECT_NEAR(below, expected_below, 0.005 * expected_below);
}

TEST(Photons, AreaLightPowerIsConservedAndFallsOnAReceiverAsItsFormFactorSays) {
    // A square light (side 1, color c, intensity 3) at height 1 over a diffuse square receiver of
    // side 2 centred below it (d 0.5, kr 0.3 reflects onto nothing, absorbs 0.2). The light emits
    // pi x 3 c; the power reaching the receiver first is that times its form factor, between the
    // nominal square's and the square grown by the splat radius (the disks reach past the edges).
    test::TestModel m =
        test::make_model(test::rect_points({-1, 0, -1}, {2, 0, 0}, {0, 0, 2}, {0, 1, 0}, 200), {0, 0, 0});
    const auto pool = test::make_pool(m);
    const rt::RenderScene rs = test::load_gi_scene(R"({
        "lights": [{"type": "area", "corner": [-0.5, 1, -0.5], "edge_u": [1, 0, 0], "edge_v": [0, 0, 1],
                    "color": [1, 0.5, 0.25], "intensity": 3}],
        "materials": [{"name": "m", "diffuse_reflectance": 0.5, "reflectivity": 0.3, "use_point_colors": false}],
        "models": [{"name": "floor", "pool": "unused.pool"}]})",
                                                   {pool});
    ASSERT_EQ(core::photon_light_count(rs.view()), 1u) << "the area light, not its samples";
    photons::ShootOptions o;
    o.params.face_res = 64;
    o.params.per_pixel = 8;
    o.backend = "cpu";
    const photons::ShootResult r = photons::shoot_photons(rs.view(), o);
    const photons::PhotonTally& t = r.tally;
    EXPECT_EQ(t.photons, photons::photons_per_light(o.params));
    const double color[3] = {3, 1.5, 0.75};
    for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(t.emitted[a], k_pi * color[a], k_pi * color[a] * 1e-4) << "channel " << a;
        const double sum = t.direct[a] + t.deposited[a] + t.absorbed[a] + t.escaped[a] + t.truncated[a];
        EXPECT_NEAR(sum, t.emitted[a], 1e-5 * t.emitted[a]) << "channel " << a;
    }
    EXPECT_EQ(t.deposits, 0u);  // a flat mirror sends nothing back to the receiver
    const double H = lum(t.direct) / 0.5;
    EXPECT_NEAR(lum(t.absorbed), 0.2 * H, 1e-4 * H);
    // Form factor light -> receiver = (1 / (pi A_light)) x the integral over the receiver of the
    // irradiance from a radiance-1 light (reciprocity), by the closed form at 64 x 64 points.
    const double r_max = *std::max_element(m.radii.begin(), m.radii.end());
    auto form_factor = [&](double half) {
        double e = 0;
        const int k = 64;
        const double step = 2 * half / k;
        for (int i = 0; i < k; ++i)
            for (int j = 0; j < k; ++j)
                e += parallel_rect_irradiance(-half + (i + 0.5) * step, -half + (j + 0.5) * step, 1.0, -0.5,
                                              0.5, -0.5, 0.5) *
                     step * step;
        return e / k_pi;
    };
    const double f = H / lum(t.emitted);
    const double f_lo = form_factor(1.0), f_hi = form_factor(1.0 + r_max);
    // 4 standard deviations of the binomial share of 393k... photons
    const double sd = std::sqrt(f_lo * (1 - f_lo) / double(t.photons));
    EXPECT_GT(f, f_lo - 4 * sd) << "form factor " << f_lo << " .. " << f_hi;
    EXPECT_LT(f, f_hi + 4 * sd) << "form factor " << f_lo << " .. " << f_hi;
}

namespace {

/// A horizontal 3 x 3 mirror (kr 1) at y = 0 facing up and a diffuse ceiling of the same size at
/// y = 2 facing down, lit by `light` (one JSON light object).
rt::RenderScene mirror_under_ceiling(const std::string& light) {
    test::TestModel mirror =
        test::make_model(test::rect_points({-1.5, 0, -1.5}, {3, 0, 0}, {0, 0, 3}, {0, 1, 0}, 150), {0, 0, 0});
    test::TestModel ceiling = test::make_model(
        test::rect_points({-1.5, 2, -1.5}, {3, 0, 0}, {0, 0, 3}, {0, -1, 0}, 150), {0, 0, 0});
    return test::load_gi_scene(R"({"lights": [)" + light + R"(],
        "materials": [{"name": "mirror", "diffuse_reflectance": 0, "reflectivity": 1},
                      {"name": "matte", "diffuse_reflectance": 1}],
        "models": [{"name": "mirror", "pool": "a.pool", "material": "mirror"},
                   {"name": "ceiling", "pool": "b.pool", "material": "matte"}]})",
                               {test::make_pool(mirror), test::make_pool(ceiling)});
}

}  // namespace

TEST(Photons, AreaLightCausticDepositsAreScaledFromTheirPointOfEmission) {
    // A tiny area light facing down over a horizontal mirror (kr 1) at y = 0, and a diffuse ceiling
    // at y = 2 above it facing down: every deposit comes from a photon that left the light near
    // (0, 1, 0), bounced at the mirror and rose to the ceiling, and carries its power x its squared
    // straight distance from the light, (2 - 1)^2 + the horizontal offset^2.
    const rt::RenderScene rs = mirror_under_ceiling(
        R"({"type": "area", "corner": [-0.005, 1, -0.005], "edge_u": [0.01, 0, 0], "edge_v": [0, 0, 0.01]})");
    photons::ShootOptions o;
    o.params.face_res = 16;
    o.params.per_pixel = 8;
    o.backend = "cpu";
    const photons::ShootResult r = photons::shoot_photons(rs.view(), o);
    ASSERT_GT(r.deposits.size(), 1000u);
    const double per_photon = k_pi / double(photons::photons_per_light(o.params));
    for (const photons::PhotonDeposit& d : r.deposits) {
        ASSERT_EQ(d.model, 1u);
        const double dx = d.position[0], dy = d.position[1] - 1.0, dz = d.position[2];
        const double d2 = dx * dx + dy * dy + dz * dz;
        ASSERT_NEAR(d.flux[0], per_photon * d2, 0.03 * per_photon * d2) << "at " << dx << ", " << dz;
    }
}

TEST(Photons, CpuDepositsAreTheSameWhateverTheThreads) {
    // Deposits are joined in photon order (per chunk), so a map is the same bytes on any machine
    // (prt-bake's Dask workers run the tools on fewer threads than a serial bake): a mirror under
    // a point light above it sends photons of several chunks to a diffuse ceiling.
    const rt::RenderScene rs = mirror_under_ceiling(R"({"type": "point", "position": [0.1, 1, 0.2]})");
    photons::ShootOptions o;
    o.params.face_res = 96;
    o.params.per_pixel = 4;  // 221k photons in 14 chunks of 16384, a face over 2.25 chunks
    o.backend = "cpu";
    o.threads = 1;
    const photons::ShootResult one = photons::shoot_photons(rs.view(), o);
    ASSERT_GT(one.deposits.size(), 2000u);
    for (unsigned threads : {2u, 3u, 7u}) {
        o.threads = threads;
        const photons::ShootResult many = photons::shoot_photons(rs.view(), o);
        ASSERT_EQ(many.deposits.size(), one.deposits.size()) << threads << " threads";
        EXPECT_EQ(std::memcmp(many.deposits.data(), one.deposits.data(),
                              one.deposits.size() * sizeof(photons::PhotonDeposit)),
                  0)
            << threads << " threads";
        for (int a = 0; a < 3; ++a) EXPECT_EQ(many.tally.deposited[a], one.tally.deposited[a]);
    }
}

namespace {

/// The ball-lens check (test below) with the ball given as a pool traced as `surface` (a glass ball
/// of radius 0.5 at the origin, in its pool's frame), the mask and the strip as splats. Also checks
/// that the photons' power is accounted for exactly.
void check_ball_lens(const std::shared_ptr<const pool::PoolFile>& ball_pool, const std::string& surface) {
    // A glass ball (n 1.5, R 0.5) at the origin, a point light on the axis at z = +2 behind a
    // mask with a small hole (paraxial rays only), and a diffuse strip in the plane y = 0 along
    // the axis behind the ball: every refracted ray stays in its meridional plane, so it meets the
    // strip where it crosses the axis. The caustic must peak at the paraxial image of the light:
    // ball lens focal length f = n R / (2 (n - 1)) from the centre (both principal planes there),
    // 1 / s_i = 1 / f - 1 / s_o.
    const double R = 0.5, n = 1.5, s_o = 2.0, hole = 0.1, mask_z = 0.8;
    const double f = n * R / (2 * (n - 1));
    const double s_i = 1.0 / (1.0 / f - 1.0 / s_o);
    // The marginal ray through the hole's edge, traced exactly (double): its axis crossing bounds
    // how far spherical aberration can move the peak from the paraxial focus.
    auto axis_crossing = [&](double h_mask) {
        const double dz = mask_z - s_o, len = std::hypot(h_mask, dz);
        double d[2] = {h_mask / len, dz / len}, o[2] = {0, s_o};  // (y, z)
        auto hit = [&](double sign) {  // sign +1: first (entering) root, -1: exit root from inside
            const double b = o[0] * d[0] + o[1] * d[1], c = o[0] * o[0] + o[1] * o[1] - R * R;
            const double t = -b - sign * std::sqrt(b * b - c);
            o[0] += t * d[0];
            o[1] += t * d[1];
        };
        auto refract = [&](double eta, double nx, double ny) {
            const double ci = -(d[0] * nx + d[1] * ny), k = 1 - eta * eta * (1 - ci * ci);
            const double s = eta * ci - std::sqrt(k);
            d[0] = eta * d[0] + s * nx;
            d[1] = eta * d[1] + s * ny;
        };
        hit(1);
        refract(1 / n, o[0] / R, o[1] / R);
        hit(-1);
        refract(n, -o[0] / R, -o[1] / R);
        return o[1] - o[0] / d[0] * d[1];  // z where y = 0
    };
    const double z_marginal = axis_crossing(hole), z_paraxial = axis_crossing(1e-4);
    ASSERT_NEAR(z_paraxial, -s_i, 1e-3) << "the paraxial formula and the exact trace disagree";

    std::vector<test::TestPoint> mask;
    for (const test::TestPoint& p : test::rect_points({-1, -1, mask_z}, {2, 0, 0}, {0, 2, 0}, {0, 0, 1}, 150))
        if (std::hypot(p.position[0], p.position[1]) > hole + p.radius) mask.push_back(p);
    std::vector<test::TestPoint> strip =
        test::rect_points({-0.3, 0, -2.5}, {0.6, 0, 0}, {0, 0, 1.95}, {0, 1, 0}, 200);
    test::TestModel mm = test::make_model(mask, {0, 0, 0}), ms = test::make_model(strip, {0, 0, 0});
    const rt::RenderScene rs = test::load_gi_scene(std::string(R"({
        "lights": [{"type": "point", "position": [0, 0, 2]}],
        "materials": [{"name": "matte"},
                      {"name": "glass", "refractive_index": 1.5, "transmissivity": 1, "diffuse_reflectance": 0}],
        "models": [{"name": "ball", "pool": "a.pool", "material": "glass", "surface": ")") +
                                                       surface + R"("},
                   {"name": "mask", "pool": "b.pool", "material": "matte"},
                   {"name": "strip", "pool": "c.pool", "material": "matte"}]})",
                                                   {ball_pool, test::make_pool(mm), test::make_pool(ms)});
    photons::ShootOptions o;
    o.params.face_res = 256;
    o.params.per_pixel = 4;
    o.backend = "cpu";
    const photons::ShootResult r = photons::shoot_photons(rs.view(), o);
    for (int a = 0; a < 3; ++a) {
        const photons::PhotonTally& t = r.tally;
        const double sum = t.direct[a] + t.deposited[a] + t.absorbed[a] + t.escaped[a] + t.truncated[a];
        EXPECT_NEAR(sum, t.emitted[a], 1e-5 * t.emitted[a]) << "power not conserved, channel " << a;
    }
    std::vector<photons::PhotonDeposit> on_strip;
    for (const photons::PhotonDeposit& d : r.deposits)
        if (d.model == 2) on_strip.push_back(d);
    ASSERT_GT(on_strip.size(), 300u);
    const double root_min[3] = {-1.3, -1.3, -2.6};
    photons::GatherOptions g;
    g.depth = 8;  // edges of 2.6 / 256 ~ 0.01
    g.radius_edges = 2;
    const gi::GiOctree tree = photons::build_caustic_octree(on_strip, root_min, 2.6, g);
    const core::GiOctreeView v = gi::view_of(tree);
    double best_z = 0, best = -1;
    for (double z = -0.6; z > -2.4; z -= 0.005) {
        const core::Vec3 e =
            core::caustic_radiance(core::CausticView{v}, core::Vec3{0, 0, float(z)}, core::Vec3{0, 1, 0});
        if (e.x > best) {
            best = e.x;
            best_z = z;
        }
    }
    const double tolerance = std::fabs(z_paraxial - z_marginal) + 2 * tree.info.gather_radius + 0.01;
    EXPECT_NEAR(best_z, -s_i, tolerance)
        << "peak at z " << best_z << ", paraxial focus " << -s_i << ", marginal " << z_marginal;
    EXPECT_LT(tolerance, 0.2 * s_i) << "the test aperture is not paraxial enough to mean anything";
    // Seen from below the strip (normal -y) there is no caustic.
    EXPECT_EQ(
        core::caustic_radiance(core::CausticView{v}, core::Vec3{0, 0, float(best_z)}, core::Vec3{0, -1, 0}).x,
        0.0f);
}

}  // namespace

TEST(Photons, BallLensFocusesWhereParaxialOpticsSays) {
    check_ball_lens(test::make_pool(test::make_model(test::sphere_points({0, 0, 0}, 0.5, 60000), {0, 0, 0})),
                    "splats");
}

TEST(Photons, BallLensFocusesOnEverySurface) {
    // Issue 20: the same ball traced as ISO and MLS (built by the tools from the ball's points, no
    // splat octree) and as 8 Bezier patches within 5e-4 R of the sphere.
    PRT_SKIP_WITHOUT_SURFACE_TOOLS();
    const test::TempDir dir("prt_photons_lens");
    test::write_points_pool(test::make_model(test::sphere_points({0, 0, 0}, 0.5, 60000), {0, 0, 0}),
                            dir.path / "ball.pool");
    test::must_run("prt-iso",
                   (dir.path / "ball.pool").string() + " -o " + (dir.path / "iso.pool").string() + " -q",
                   dir.path);
    test::must_run("prt-mls",
                   (dir.path / "ball.pool").string() + " -o " + (dir.path / "mls.pool").string() + " -q",
                   dir.path);
    const double origin[3] = {0, 0, 0};
    test::sphere_patch_file(dir.path, 0.5, origin);
    test::must_run("prt-patches",
                   (dir.path / "sphere.bpt").string() + " -o " + (dir.path / "patches.pool").string() + " -q",
                   dir.path);
    for (const char* surface : {"iso", "mls", "patches"}) {
        SCOPED_TRACE(surface);
        check_ball_lens(std::make_shared<const pool::PoolFile>(
                            pool::PoolFile::open(dir.path / (std::string(surface) + ".pool"))),
                        surface);
    }
}

namespace {

/// The caustic on a floor (z = -1.4, 2 x 2, facing +z) under a glass ball (R 0.5 at the origin, as
/// splats) lit from z = 3, with the floor given as a pool traced as `surface`: the floor's caustic
/// octree built as prt-photons builds it (its GI frame, --caustic-levels 2, gather radius 1 edge)
/// and looked up on a 101 x 101 grid over [-0.5, 0.5]^2 of the floor.
std::vector<double> floor_caustic(const std::shared_ptr<const pool::PoolFile>& floor,
                                  const std::string& surface, gi::GiFrame& frame, std::uint32_t depth = 0) {
    const auto ball =
        test::make_pool(test::make_model(test::sphere_points({0, 0, 0}, 0.5, 60000), {0, 0, 0}));
    const rt::RenderScene rs = test::load_gi_scene(std::string(R"({
        "lights": [{"type": "point", "position": [0, 0, 3]}],
        "materials": [{"name": "matte"},
                      {"name": "glass", "refractive_index": 1.5, "transmissivity": 1, "diffuse_reflectance": 0}],
        "models": [{"name": "ball", "pool": "a.pool", "material": "glass"},
                   {"name": "floor", "pool": "b.pool", "material": "matte", "surface": ")") +
                                                       surface + R"("}]})",
                                                   {ball, floor});
    photons::ShootOptions o;
    o.params.face_res = 512;
    o.params.per_pixel = 4;
    o.backend = "cpu";
    const photons::ShootResult r = photons::shoot_photons(rs.view(), o);
    std::vector<photons::PhotonDeposit> on_floor;
    for (const photons::PhotonDeposit& d : r.deposits)
        if (d.model == 1) on_floor.push_back(d);
    const gi::SurfacePoints points = gi::surface_points(*floor);
    frame = gi::gi_frame(*floor, &points);
    photons::GatherOptions g;
    g.depth = depth > 0 ? depth : frame.depth + 2;
    const gi::GiOctree tree = photons::build_caustic_octree(on_floor, frame.root_min, frame.root_size, g);
    const core::CausticView v{gi::view_of(tree)};
    const core::ModelView& mv = rs.view().models[1];  // the map is in the floor pool's local frame
    std::vector<double> grid;
    for (int i = 0; i <= 100; ++i)
        for (int j = 0; j <= 100; ++j) {
            const core::Vec3 world{-0.5f + 0.01f * i, -0.5f + 0.01f * j, -1.4f};
            const core::Vec3 local = core::mul_transpose(mv.rotation, world - mv.offset) * mv.inv_scale;
            grid.push_back(core::caustic_radiance(v, local, core::Vec3{0, 0, 1}).x);
        }
    return grid;
}

}  // namespace

TEST(Photons, ThePatchFloorsCausticMatchesTheSplatFloors) {
    // Issue 20's target: the caustic under a glass sphere on a patch floor matches the splat-floor
    // caustic. The same photons reach both floors (the splat floor's discs lie in its plane); the
    // maps differ in their frames (the splat octree's root and depth against the cube and level of
    // the points sampled on the patch: one level finer here), so their leaves differ in size and
    // placement. Measured (2026-11-25, dev VM; 6.3M photons, about 20 000 deposits): at the default
    // levels total ratio 1.028, binned L1 0.051; at the same level total ratio 1.032, pointwise L1
    // 0.135, binned L1 0.034, peak ratio 1.039. Stated tolerance: totals within 5 %, binned L1
    // below 8 % of the total; at the same level the pointwise L1 below 20 %, the peaks within 10 %.
    PRT_SKIP_WITHOUT_SURFACE_TOOLS();
    const test::TempDir dir("prt_photons_floor");
    test::flat_patch_file(dir.path, -1, -1, -1.4, 2.0);
    test::must_run("prt-patches",
                   (dir.path / "flat.bpt").string() + " -o " + (dir.path / "floor.pool").string() + " -q",
                   dir.path);
    // The splat floor from the real octree builder (prt-octree), like the patch floor from prt-patches.
    test::write_points_pool(
        test::make_model(test::rect_points({-1, -1, -1.4}, {2, 0, 0}, {0, 2, 0}, {0, 0, 1}, 200), {0, 0, 0}),
        dir.path / "points.pool");
    test::must_run("prt-octree",
                   (dir.path / "points.pool").string() + " -o " + (dir.path / "splats.pool").string() + " -q",
                   dir.path);
    const auto splat_floor =
        std::make_shared<const pool::PoolFile>(pool::PoolFile::open(dir.path / "splats.pool"));
    const auto patch_floor =
        std::make_shared<const pool::PoolFile>(pool::PoolFile::open(dir.path / "floor.pool"));
    // Compared pointwise on the grid, and binned into 10 x 10 squares of 0.1 (how the caustic's
    // power is distributed, whatever the maps' cell sizes).
    struct Compare {
        double total_ratio, l1, peak_ratio, binned_l1;
    };
    auto compare = [](const std::vector<double>& a, const std::vector<double>& b) {
        double sa = 0, sb = 0, diff = 0, pa = 0, pb = 0;
        double ba[10][10] = {}, bb[10][10] = {};
        for (std::size_t k = 0; k < a.size(); ++k) {
            sa += a[k];
            sb += b[k];
            diff += std::fabs(a[k] - b[k]);
            pa = std::max(pa, a[k]);
            pb = std::max(pb, b[k]);
            const int i = std::min(9, int(k / 101) / 10), j = std::min(9, int(k % 101) / 10);
            ba[i][j] += a[k];
            bb[i][j] += b[k];
        }
        double bdiff = 0;
        for (int i = 0; i < 10; ++i)
            for (int j = 0; j < 10; ++j) bdiff += std::fabs(ba[i][j] - bb[i][j]);
        return Compare{sb / sa, diff / sa, pb / pa, bdiff / sa};
    };
    gi::GiFrame fs, fp;
    const std::vector<double> a = floor_caustic(splat_floor, "splats", fs);
    const std::vector<double> b = floor_caustic(patch_floor, "patches", fp);
    EXPECT_EQ(fs.from, "the splat octree");
    EXPECT_EQ(fp.from, "the patches");
    ASSERT_GT(*std::max_element(a.begin(), a.end()), 0.0);
    const Compare d = compare(a, b);
    // The same maps' leaf level for both (the splat floor's default): what the surface changes alone.
    gi::GiFrame unused;
    const Compare e = compare(a, floor_caustic(patch_floor, "patches", unused, fs.depth + 2));
    std::printf(
        "caustic, patch floor vs splat floor: default levels (%u / %u): total ratio %.4f, L1 %.4f, binned "
        "L1 %.4f, peak ratio %.4f; same level: total ratio %.4f, L1 %.4f, binned L1 %.4f, peak ratio %.4f\n",
        fs.depth + 2, fp.depth + 2, d.total_ratio, d.l1, d.binned_l1, d.peak_ratio, e.total_ratio, e.l1,
        e.binned_l1, e.peak_ratio);
    EXPECT_NEAR(d.total_ratio, 1.0, 0.05);
    EXPECT_LT(d.binned_l1, 0.08);
    EXPECT_NEAR(e.total_ratio, 1.0, 0.05);
    EXPECT_LT(e.binned_l1, 0.08);
    EXPECT_LT(e.l1, 0.2);
    EXPECT_NEAR(e.peak_ratio, 1.0, 0.1);
}

TEST(GiFrame, PointsGiveTheSplatOctreesLevelWithinOne) {
    // gi_frame.h: without a splat octree the reference level is the first at which the points fill
    // their cells 8 to a cell on average; on uniformly sampled surfaces it is the octree's depth
    // within one level. The root holds every point.
    for (std::size_t n : {20000u, 200000u}) {
        const test::TestModel m = test::make_model(test::sphere_points({0, 0, 0}, 1.0, n), {0, 0, 0});
        const auto with_octree = test::make_pool(m);
        const gi::GiFrame octree = gi::gi_frame(*with_octree, nullptr);
        EXPECT_EQ(octree.from, "the splat octree");
        const gi::SurfacePoints points = gi::surface_points(*with_octree);
        ASSERT_EQ(points.position.size(), n);
        gi::GiFrame own;
        own.depth = gi::reference_level(points.position, octree.root_min, octree.root_size);
        EXPECT_LE(std::abs(int(own.depth) - int(octree.depth)), 1) << n << " points";
        const gi::GiFrame pts = [&] {
            pool::PoolWriter w;
            w.carry_over(*with_octree);
            for (pool::SectionType t : {pool::SectionType::octree_info, pool::SectionType::octree_nodes,
                                        pool::SectionType::leaf_info, pool::SectionType::splats})
                w.remove(t);
            const pool::PoolFile f = pool::PoolFile::from_bytes(w.serialize(), "points");
            return gi::gi_frame(f, &points);
        }();
        EXPECT_EQ(pts.from, "the points");
        for (const core::Vec3& p : points.position)
            for (int a = 0; a < 3; ++a) {
                const double c = a == 0 ? p.x : a == 1 ? p.y : p.z;
                ASSERT_GT(c, pts.root_min[a]);
                ASSERT_LT(c, pts.root_min[a] + pts.root_size);
            }
    }
}

TEST(Photons, CausticOctreeEstimatesAKnownIrradiance) {
    // Deposits spread uniformly over a unit square of the plane y = 0 carrying a total flux P give
    // E = P / area everywhere inside (eq. 5.1-5.2 is a normalised kernel).
    std::vector<photons::PhotonDeposit> deps;
    const int side = 300;
    const float flux = 2.0f / (side * side);  // P = 2 on an area of 1: E = 2
    for (int i = 0; i < side; ++i)
        for (int j = 0; j < side; ++j) {
            const std::uint64_t h = photons::hash64(i * 1000003ull + j);
            photons::PhotonDeposit d{};
            d.position[0] = (i + photons::unit_float(h)) / side - 0.5f;
            d.position[2] = (j + photons::unit_float(photons::hash64(h))) / side - 0.5f;
            d.flux[0] = d.flux[1] = d.flux[2] = flux;
            d.normal[1] = 1;
            deps.push_back(d);
        }
    const double root_min[3] = {-1, -1, -1};
    photons::GatherOptions g;
    g.depth = 7;  // edge 2 / 128
    g.radius_edges = 1.5f;
    const gi::GiOctree tree = photons::build_caustic_octree(deps, root_min, 2.0, g);
    const core::GiOctreeView v = gi::view_of(tree);
    double sum = 0;
    int n = 0;
    for (int i = 0; i < 40; ++i) {
        const core::Vec3 p{-0.4f + 0.8f * i / 39.0f, 0.0f, 0.3f - 0.6f * ((i * 7) % 40) / 39.0f};
        const core::Vec3 e = core::caustic_radiance(core::CausticView{v}, p, core::Vec3{0, 1, 0});
        EXPECT_NEAR(e.y, 2.0, 0.15) << "at " << p.x << ", " << p.z;
        sum += e.y;
        ++n;
    }
    EXPECT_NEAR(sum / n, 2.0, 0.04);
    // Far from any deposit: nothing.
    EXPECT_EQ(core::caustic_radiance(core::CausticView{v}, core::Vec3{0, 0.5f, 0}, core::Vec3{0, 1, 0}).y,
              0.0f);
}

namespace {

// A serial caustic gather written straight from thesis 5.4.2 / eq. 5.1-5.2, with ordered maps and
// no blocks, hashes or threads: the reference the parallel build_caustic_octree must match. Sums
// are in double (so they match to rounding, not bit for bit); the kernel test r^2 < g^2 is the
// same float expression, so the corner and leaf sets must match exactly.
struct ReferenceGather {
    std::vector<std::uint64_t> keys;  ///< leaves, Morton order
    std::vector<std::array<std::array<double, 3>, 8>> corner;
    std::vector<std::array<double, 3>> normal;
    double max_value = 0;
    std::vector<std::uint32_t> nodes;  ///< breadth first, from sets of prefixes per level
};

ReferenceGather reference_gather(const std::vector<photons::PhotonDeposit>& deps, const double root_min[3],
                                 double root_size, std::uint32_t depth, float radius_edges, float scale) {
    using Cell = std::array<std::int64_t, 3>;
    const std::int64_t cells = std::int64_t{1} << depth;
    const double ge = radius_edges;
    const std::int64_t r = static_cast<std::int64_t>(std::ceil(ge));
    std::map<Cell, std::vector<std::size_t>> in_cell;
    std::vector<std::array<float, 3>> frac(deps.size());
    for (std::size_t i = 0; i < deps.size(); ++i) {
        Cell c;
        for (int a = 0; a < 3; ++a) {
            const double g = (static_cast<double>(deps[i].position[a]) - root_min[a]) / root_size *
                             static_cast<double>(cells);
            c[a] = static_cast<std::int64_t>(std::clamp(std::floor(g), 0.0, static_cast<double>(cells - 1)));
            frac[i][a] = static_cast<float>(g - static_cast<double>(c[a]));
        }
        in_cell[c].push_back(i);
    }
    struct Sum {
        double value[3] = {0, 0, 0}, normal[3] = {0, 0, 0}, weight = 0;
    };
    std::map<Cell, Sum> corners;
    for (const auto& [c, list] : in_cell)
        for (std::int64_t z = std::max<std::int64_t>(0, c[2] - r + 1); z <= std::min(cells, c[2] + r); ++z)
            for (std::int64_t y = std::max<std::int64_t>(0, c[1] - r + 1); y <= std::min(cells, c[1] + r);
                 ++y)
                for (std::int64_t x = std::max<std::int64_t>(0, c[0] - r + 1); x <= std::min(cells, c[0] + r);
                     ++x)
                    corners[Cell{x, y, z}];
    const double edge = root_size / static_cast<double>(cells) * scale;
    const double norm = 2.0 / (k_pi * (ge * edge) * (ge * edge));
    const float inv_g2 = static_cast<float>(1.0 / (ge * ge));
    for (auto& [q, sum] : corners)
        for (const auto& [c, list] : in_cell) {
            bool near = true;
            for (int a = 0; a < 3; ++a) near = near && c[a] >= q[a] - r && c[a] <= q[a] + r - 1;
            if (!near) continue;
            for (std::size_t i : list) {
                float d2 = 0;
                const float dx = static_cast<float>(c[0] - q[0]) + frac[i][0];
                const float dy = static_cast<float>(c[1] - q[1]) + frac[i][1];
                const float dz = static_cast<float>(c[2] - q[2]) + frac[i][2];
                d2 = (dx * dx + dy * dy + dz * dz) * inv_g2;
                if (!(d2 < 1.0f)) continue;
                const double w = 1.0 - d2;
                const double l =
                    0.2126 * deps[i].flux[0] + 0.7152 * deps[i].flux[1] + 0.0722 * deps[i].flux[2];
                for (int a = 0; a < 3; ++a) {
                    sum.value[a] += w * deps[i].flux[a] * norm;
                    sum.normal[a] += w * l * deps[i].normal[a];
                }
                sum.weight += w * l;
            }
        }
    std::map<std::uint64_t, Cell> leaves;  // by Morton key
    for (const auto& [q, sum] : corners) {
        if (!(sum.value[0] > 0 || sum.value[1] > 0 || sum.value[2] > 0)) continue;
        for (int d = 0; d < 8; ++d) {
            const Cell v{q[0] - (d & 1), q[1] - ((d >> 1) & 1), q[2] - ((d >> 2) & 1)};
            if (std::min({v[0], v[1], v[2]}) < 0 || std::max({v[0], v[1], v[2]}) >= cells) continue;
            leaves[pre::morton3(static_cast<std::uint32_t>(v[0]), static_cast<std::uint32_t>(v[1]),
                                static_cast<std::uint32_t>(v[2]))] = v;
        }
    }
    ReferenceGather ref;
    for (const auto& [key, v] : leaves) {
        ref.keys.push_back(key);
        std::array<std::array<double, 3>, 8> corner{};
        double n[3] = {0, 0, 0}, w = 0;
        for (int c = 0; c < 8; ++c) {
            const auto it = corners.find(Cell{v[0] + (c & 1), v[1] + ((c >> 1) & 1), v[2] + ((c >> 2) & 1)});
            if (it == corners.end()) continue;
            for (int a = 0; a < 3; ++a) {
                corner[c][a] = it->second.value[a];
                ref.max_value = std::max(ref.max_value, corner[c][a]);
                n[a] += it->second.normal[a];
            }
            w += it->second.weight;
        }
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        std::array<double, 3> nn{0, 0, 0};
        if (w > 0 && len >= 0.5 * w)
            for (int a = 0; a < 3; ++a) nn[a] = n[a] / len;
        ref.corner.push_back(corner);
        ref.normal.push_back(nn);
    }
    // Nodes: the internal nodes of each level as ordered sets, laid out breadth first (8 slots per
    // internal node, children in Morton order; pool_layout.h).
    std::vector<std::set<std::uint64_t>> level(depth + 1);
    level[depth].insert(ref.keys.begin(), ref.keys.end());
    for (std::uint32_t l = depth; l-- > 0;)
        for (std::uint64_t k : level[l + 1]) level[l].insert(k >> 3);
    ref.nodes.assign(1, pool::make_node(pool::NodeType::empty_leaf, 0));
    if (ref.keys.empty()) return ref;
    if (depth == 0) {
        ref.nodes[0] = pool::make_node(pool::NodeType::filled_leaf, 0);
        return ref;
    }
    std::map<std::uint64_t, std::size_t> slot_of{{0, 0}};  // node of a prefix at the current level
    for (std::uint32_t l = 0; l < depth; ++l) {
        std::map<std::uint64_t, std::size_t> next;
        std::size_t i = 0, leaf = 0;
        const std::size_t base = ref.nodes.size();
        ref.nodes.resize(base + 8 * level[l].size(), pool::make_node(pool::NodeType::empty_leaf, 0));
        for (std::uint64_t p : level[l]) {
            ref.nodes[slot_of.at(p)] =
                pool::make_node(pool::NodeType::internal, static_cast<std::uint32_t>(base + 8 * i));
            for (std::uint64_t child = p << 3; child < (p << 3) + 8; ++child)
                if (level[l + 1].count(child)) next[child] = base + 8 * i + (child & 7);
            ++i;
        }
        if (l + 1 == depth)
            for (const auto& [k, slot] : next)
                ref.nodes[slot] =
                    pool::make_node(pool::NodeType::filled_leaf, static_cast<std::uint32_t>(leaf++));
        slot_of.swap(next);
    }
    return ref;
}

/// Deposits in every octant: a blurred shell with colours and both-sided normals, plus a floor on
/// the plane y = 0 (a cell boundary at every depth) and a dense clump.
std::vector<photons::PhotonDeposit> mixed_deposits(std::size_t n) {
    std::vector<photons::PhotonDeposit> deps(n);
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint64_t h = photons::hash64(i + 17);
        const float u = photons::unit_float(h), v = photons::unit_float(photons::hash64(h)),
                    w = photons::unit_float(photons::hash64(h + 1));
        photons::PhotonDeposit& d = deps[i];
        d = {};
        const float z = 2 * u - 1, s = std::sqrt(std::max(0.0f, 1 - z * z)), t = 6.2831853f * v;
        const float dir[3] = {s * std::cos(t), s * std::sin(t), z};
        for (int a = 0; a < 3; ++a) {
            if (i % 3 == 0) {
                d.position[a] = a == 1 ? 0.0f : 1.6f * (a == 0 ? u : v) - 0.8f;
                d.normal[a] = a == 1 ? 1.0f : 0.0f;
            } else if (i % 7 == 1) {
                d.position[a] = 0.3f + 0.05f * dir[a] * w;
                d.normal[a] = dir[a];
            } else {
                d.position[a] = (0.6f + 0.05f * w) * dir[a];
                d.normal[a] = (i % 2 ? 1.0f : -1.0f) * dir[a];
            }
            d.flux[a] = 1e-3f * (0.5f + w * static_cast<float>(a + 1));
        }
    }
    return deps;
}

}  // namespace

TEST(Photons, CausticOctreeMatchesASerialReferenceWhateverTheThreads) {
    const std::vector<photons::PhotonDeposit> deps = mixed_deposits(6000);
    const double root_min[3] = {-1, -1, -1};
    struct Case {
        std::uint32_t depth;
        float radius;
    };
    for (const Case cs : {Case{6, 1.0f}, Case{5, 1.6f}, Case{4, 0.5f}, Case{2, 3.0f}, Case{0, 1.0f}}) {
        SCOPED_TRACE("depth " + std::to_string(cs.depth) + ", radius " + std::to_string(cs.radius));
        photons::GatherOptions g;
        g.depth = cs.depth;
        g.radius_edges = cs.radius;
        g.render_scale = 2.0f;
        g.threads = 1;
        const gi::GiOctree one = photons::build_caustic_octree(deps, root_min, 2.0, g);
        for (unsigned threads : {3u, 8u}) {  // byte-identical whatever the thread count
            g.threads = threads;
            const gi::GiOctree many = photons::build_caustic_octree(deps, root_min, 2.0, g);
            EXPECT_EQ(many.nodes, one.nodes);
            ASSERT_EQ(many.leaves.size(), one.leaves.size());
            EXPECT_EQ(
                std::memcmp(many.leaves.data(), one.leaves.data(), one.leaves.size() * sizeof(pool::GiLeaf)),
                0);
            EXPECT_EQ(std::memcmp(&many.info, &one.info, sizeof one.info), 0);
        }
        const ReferenceGather ref = reference_gather(deps, root_min, 2.0, cs.depth, cs.radius, 2.0f);
        ASSERT_GT(ref.keys.size(), 0u);
        EXPECT_EQ(one.nodes, ref.nodes);  // same leaves at the same places
        ASSERT_EQ(one.leaves.size(), ref.keys.size());
        EXPECT_NEAR(one.info.scale, ref.max_value / 32768.0, ref.max_value / 32768.0 * 1e-5);
        const double step = one.info.scale * 6e-8;  // RGB9E5's smallest step, in values
        for (std::size_t j = 0; j < ref.keys.size(); ++j) {
            for (int c = 0; c < 8; ++c) {
                const core::Vec3 e = core::decode_rgb9e5(one.leaves[j].corner[c]) * one.info.scale;
                const double top = std::max({ref.corner[j][c][0], ref.corner[j][c][1], ref.corner[j][c][2]});
                const double got[3] = {e.x, e.y, e.z};
                for (int a = 0; a < 3; ++a)
                    ASSERT_NEAR(got[a], ref.corner[j][c][a], top * 2.0 / 512 + step)
                        << "leaf " << j << " corner " << c;
            }
            for (int a = 0; a < 3; ++a)
                ASSERT_NEAR(one.leaves[j].normal[a], ref.normal[j][a] * 127.0, 1.0) << "leaf " << j;
        }
    }
}

TEST(Photons, Rgb9e5RoundTrip) {
    for (float v : {1e-6f, 0.003f, 0.5f, 1.0f, 7.25f, 1234.5f, 60000.0f}) {
        const core::Vec3 c{v, v * 0.5f, v * 0.25f};
        const core::Vec3 d = core::decode_rgb9e5(core::encode_rgb9e5(c));
        EXPECT_NEAR(d.x, c.x, c.x * 2.0f / 512 + 6e-8f) << v;  // + the smallest step, 2^-24
        EXPECT_NEAR(d.y, c.y, c.x * 2.0f / 512 + 6e-8f) << v;
        EXPECT_NEAR(d.z, c.z, c.x * 2.0f / 512 + 6e-8f) << v;
    }
    EXPECT_EQ(core::encode_rgb9e5(core::Vec3{-1, std::nanf(""), 0}), 0u);
}

TEST(Photons, LoaderRejectsBrokenSections) {
    std::vector<gi::LeafValues> leaves(2);
    for (std::uint64_t k = 0; k < 2; ++k) {
        leaves[k] = {};
        leaves[k].key = k * 9;
    }
    const double root_min[3] = {0, 0, 0};
    gi::GiOctree tree = gi::build_octree(leaves, root_min, 1.0, 2);
    tree.info.gather_radius = 0.1f;
    auto pool_with = [&](const gi::GiOctree& t) {
        test::TestModel m = test::make_model(test::sphere_points({0, 0, 0}, 1, 500), {0, 0, 0});
        const auto base = test::make_pool(m);  // carried sections are views: keep it alive
        pool::PoolWriter w;
        w.carry_over(*base);
        w.add_array(pool::SectionType::caustic_info, std::vector<pool::GiInfo>{t.info});
        w.add_array(pool::SectionType::caustic_nodes, t.nodes);
        w.add_array(pool::SectionType::caustic_leaves, t.leaves);
        return pool::PoolFile::from_bytes(w.serialize(), "m.pool");
    };
    const core::CausticView ok = rt::load_caustic_view(pool_with(tree));
    EXPECT_EQ(ok.tree.leaf_count, 2u);
    gi::GiOctree bad = tree;
    bad.nodes[0] = pool::make_node(pool::NodeType::internal, 0);  // its own child
    try {
        rt::load_caustic_view(pool_with(bad));
        FAIL() << "accepted a node pointing backwards";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("m.pool: section caustic_nodes"), std::string::npos) << e.what();
    }
    bad = tree;
    bad.info.depth = 3;  // leaves at level 2
    EXPECT_THROW(rt::load_caustic_view(pool_with(bad)), Error);
    bad = tree;
    bad.info.scale = -1;
    EXPECT_THROW(rt::load_caustic_view(pool_with(bad)), Error);
}

TEST(Photons, APoolHoldsOneCausticMapPerPlacement) {
    // Issue 20: caustic_info holds one GiInfo per map, the nodes and leaves follow one another; each
    // map is found by its placement key, a map keyed 0 serves any placement; keys must be distinct
    // and non-zero when there are several maps.
    auto tree_with = [](std::uint32_t leaf_count, std::uint32_t placement) {
        std::vector<gi::LeafValues> leaves(leaf_count);
        for (std::uint32_t k = 0; k < leaf_count; ++k) {
            leaves[k] = {};
            leaves[k].key = k * 9;
        }
        const double root_min[3] = {0, 0, 0};
        gi::GiOctree t = gi::build_octree(leaves, root_min, 1.0, 2);
        t.info.gather_radius = 0.1f;
        t.info.placement = placement;
        return t;
    };
    test::TestModel m = test::make_model(test::sphere_points({0, 0, 0}, 1, 500), {0, 0, 0});
    const auto base = test::make_pool(m);
    auto pool_with = [&](const std::vector<gi::GiOctree>& trees) {
        std::vector<pool::GiInfo> infos;
        std::vector<std::uint32_t> nodes;
        std::vector<pool::GiLeaf> leaves;
        for (const gi::GiOctree& t : trees) {
            infos.push_back(t.info);
            nodes.insert(nodes.end(), t.nodes.begin(), t.nodes.end());
            leaves.insert(leaves.end(), t.leaves.begin(), t.leaves.end());
        }
        pool::PoolWriter w;
        w.carry_over(*base);
        w.add_array(pool::SectionType::caustic_info, infos);
        w.add_array(pool::SectionType::caustic_nodes, nodes);
        w.add_array(pool::SectionType::caustic_leaves, leaves);
        return pool::PoolFile::from_bytes(w.serialize(), "m.pool");
    };
    const pool::PoolFile two = pool_with({tree_with(3, 7), tree_with(1, 9)});
    const std::vector<pool::GiSections> maps = pool::validate_caustic_maps(two);
    ASSERT_EQ(maps.size(), 2u);
    EXPECT_EQ(maps[0].leaves.size(), 3u);
    EXPECT_EQ(maps[1].leaves.size(), 1u);
    EXPECT_EQ(maps[1].nodes.data(), maps[0].nodes.data() + maps[0].nodes.size());
    EXPECT_EQ(rt::load_caustic_view(two, 7).tree.leaf_count, 3u);
    EXPECT_EQ(rt::load_caustic_view(two, 9).tree.leaf_count, 1u);
    EXPECT_EQ(rt::load_caustic_view(two, 8).tree.nodes, nullptr) << "no map for that placement";
    EXPECT_THROW((void)pool::validate_caustics(two), Error) << "the single-map reader";
    // One map keyed 0 serves every placement (pools written before issue 20, or placed once).
    const pool::PoolFile any = pool_with({tree_with(2, 0)});
    EXPECT_EQ(rt::load_caustic_view(any, 12345).tree.leaf_count, 2u);
    // Broken: equal keys, a zero key among several, the arrays longer than the infos say.
    for (const auto& [bad, what] : std::vector<std::pair<std::vector<gi::GiOctree>, std::string>>{
             {{tree_with(2, 7), tree_with(1, 7)}, "map 1: the placement key of map 0"},
             {{tree_with(2, 7), tree_with(1, 0)}, "map 1: placement key 0 among several maps"}}) {
        try {
            (void)pool::validate_caustic_maps(pool_with(bad));
            FAIL() << "accepted: " << what;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("m.pool: section caustic_info: " + what), std::string::npos)
                << e.what();
        }
    }
    gi::GiOctree short_info = tree_with(2, 7);
    short_info.info.leaf_count = 1;
    short_info.info.node_count = 1;
    EXPECT_THROW((void)pool::validate_caustic_maps(pool_with({short_info, tree_with(1, 9)})), Error);
    // Keys: a hash of the transform, never 0; different placements differ.
    scene::Transform a, b;
    b.translate = {1, 0, 0};
    EXPECT_NE(pool::placement_key(a), 0u);
    EXPECT_NE(pool::placement_key(a), pool::placement_key(b));
    EXPECT_EQ(pool::placement_key(b), pool::placement_key(b));
}

TEST(GiBuild, RadixOrderAndSortUniqueAgreeWithTheStandardLibrary) {
    std::vector<std::uint64_t> keys(300000);
    for (std::size_t i = 0; i < keys.size(); ++i)
        keys[i] = photons::hash64(i) & ((1ull << 40) - 1) & ~0xffull;
    const std::vector<std::uint32_t> order = gi::radix_order(keys, 40);
    std::vector<std::uint32_t> expected(keys.size());
    for (std::size_t i = 0; i < keys.size(); ++i) expected[i] = static_cast<std::uint32_t>(i);
    std::stable_sort(expected.begin(), expected.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return keys[a] < keys[b]; });
    EXPECT_EQ(order, expected);
    std::vector<std::uint64_t> u = keys, su = keys;
    gi::sort_unique(u, 40);
    std::sort(su.begin(), su.end());
    su.erase(std::unique(su.begin(), su.end()), su.end());
    EXPECT_EQ(u, su);
}

TEST(Photons, RendererAddsTheCausticTimesTheAlbedo) {
    // A plane whose pool carries a caustic octree of uniform irradiance E = 2 (deposits as in
    // CausticOctreeEstimatesAKnownIrradiance): with render.caustics on, a camera ray hitting it
    // gains diffuse x d x E; with it off (or the sections absent, with a warning) nothing changes.
    test::TestModel m =
        test::make_model(test::rect_points({-0.5, 0, -0.5}, {1, 0, 0}, {0, 0, 1}, {0, 1, 0}, 120), {0, 0, 0});
    std::vector<photons::PhotonDeposit> deps;
    const int side = 200;
    for (int i = 0; i < side; ++i)
        for (int j = 0; j < side; ++j) {
            photons::PhotonDeposit d{};
            d.position[0] = (i + 0.5f) / side - 0.5f;
            d.position[2] = (j + 0.5f) / side - 0.5f;
            d.flux[0] = d.flux[1] = d.flux[2] = 2.0f / (side * side);
            d.normal[1] = 1;
            deps.push_back(d);
        }
    double root_min[3], root_size;
    std::uint32_t depth;
    const auto plain = test::make_pool(m);
    gi::splat_root(*plain, root_min, root_size, depth);
    photons::GatherOptions g;
    g.depth = depth + 1;
    g.radius_edges = 1.5f;
    const gi::GiOctree tree = photons::build_caustic_octree(deps, root_min, root_size, g);
    pool::PoolWriter w;
    w.carry_over(*plain);
    w.add_array(pool::SectionType::caustic_info, std::vector<pool::GiInfo>{tree.info});
    w.add_array(pool::SectionType::caustic_nodes, tree.nodes);
    w.add_array(pool::SectionType::caustic_leaves, tree.leaves);
    const auto with =
        std::make_shared<const pool::PoolFile>(pool::PoolFile::from_bytes(w.serialize(), "plane.pool"));
    auto scene = [](bool caustics) {
        return std::string(R"({"lights": [{"type": "point", "position": [0, 1, 0], "casts_shadows": false}],
            "materials": [{"name": "m", "ambient": [0, 0, 0], "diffuse": [0.5, 0.5, 0.5], "specular": [0, 0, 0],
                           "diffuse_reflectance": 0.8, "use_point_colors": false}],
            "models": [{"name": "plane", "pool": "plane.pool"}],
            "environment": {"color": [0, 0, 0]}, "render": {"caustics": )") +
               (caustics ? "true" : "false") + "}}";
    };
    const core::Ray down{core::Vec3{0.1f, 1.0f, 0.05f}, core::Vec3{0, -1, 0}, core::k_inf, 0u};
    auto radiance = [&](const rt::RenderScene& rs) {
        core::RayCounters c;
        return core::trace_ray(rs.view(), down, c);
    };
    const rt::RenderScene on = test::load_gi_scene(scene(true), {with});
    const rt::RenderScene off = test::load_gi_scene(scene(false), {with});
    const rt::RenderScene missing = test::load_gi_scene(scene(true), {plain});
    const core::Vec3 a = radiance(on), b = radiance(off), c = radiance(missing);
    EXPECT_NEAR(a.y - b.y, 0.5 * 0.8 * 2.0, 0.05);
    EXPECT_EQ(b.y, c.y);
    bool warned = false;
    for (const std::string& s : missing.warnings())
        warned = warned || s.find("no caustic octree") != std::string::npos;
    EXPECT_TRUE(warned);
}
