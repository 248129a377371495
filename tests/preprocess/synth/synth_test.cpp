// prt-synth: points on the analytic surfaces with true normals, area uniformity, noise bounds,
// determinism, scale/offset, the pool round trip and the command line. Surface and normal checks use
// each shape's implicit equation written out here, not analytic.h's code.
#include "synth.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "point_cloud.h"
#include "prt/formats/pool.h"
#include "synth_test_util.h"

namespace fs = std::filesystem;
using namespace prt::synth;
using prt::synth_test::ToolDir;
using prt::synth_test::ToolRun;

namespace {

constexpr double k_pi = 3.14159265358979323846;

Shape make_shape(ShapeKind kind) {
    return prt::synth_test::make_shape(kind, {1.25, {1.0, 0.35}, 1.5, 3.0});
}

SynthResult run(ShapeKind kind, std::uint64_t n, Sampling sampling = Sampling::r2,
                ColorMode colors = ColorMode::parts, double noise = 0.0, std::uint64_t seed = 1,
                unsigned threads = 0) {
    SynthOptions o;
    o.shape = make_shape(kind);
    o.count = n;
    o.sampling = sampling;
    o.colors = colors;
    o.noise = noise;
    o.seed = seed;
    o.threads = threads;
    return synthesize(o);
}

double len(const Vec3& a) {
    return std::hypot(a[0], a[1], a[2]);
}

/// Independent check of one point: its distance to the surface (from the implicit equation, or
/// the face plane) and the true normal there, in the shape's local frame. For the room the part
/// comes from the point's color.
struct Check {
    double distance = INFINITY;  ///< |signed distance|
    Vec3 normal{};
};

/// Distance to a face of an axis-aligned box of half edge h (axis a, side s) and its normal.
Check box_face_check(const Vec3& q, double h, int a, double s) {
    Check c;
    double out = 0;
    for (int b = 0; b < 3; ++b)
        if (b != a) out = std::max(out, std::fabs(q[b]) - h);
    c.distance = std::fabs(q[a] - s * h) + std::max(0.0, out);
    c.normal = {0, 0, 0};
    c.normal[a] = s;
    return c;
}

/// The face of a box the normal names (axis of the non-zero component, its sign).
Check cube_check(const Vec3& q, double h, const prt::pool::Float3& n) {
    const float m[3] = {n.x, n.y, n.z};
    int a = 0;
    for (int b = 1; b < 3; ++b)
        if (std::fabs(m[b]) > std::fabs(m[a])) a = b;
    return box_face_check(q, h, a, m[a] < 0 ? -1.0 : 1.0);
}

Check check_point(const Shape& s, const Vec3& p, const prt::pool::Float3& n, prt::pool::Rgba8 color) {
    Check c;
    switch (s.kind) {
        case ShapeKind::sphere:
            c.distance = std::fabs(len(p) - s.sphere.radius);
            c.normal = {p[0] / len(p), p[1] / len(p), p[2] / len(p)};
            break;
        case ShapeKind::torus: {
            const double q = std::hypot(p[0], p[2]) - s.torus.major_radius;
            const double tube = std::hypot(q, p[1]);
            c.distance = std::fabs(tube - s.torus.minor_radius);
            const double rho = std::hypot(p[0], p[2]);
            c.normal = {q * p[0] / rho / tube, p[1] / tube, q * p[2] / rho / tube};
            break;
        }
        case ShapeKind::cube:
            c = cube_check(p, 0.5 * s.cube.edge, n);
            break;
        case ShapeKind::plane: {
            const double h = 0.5 * s.plane.size;
            c.distance = std::fabs(p[1]) + std::max({0.0, std::fabs(p[0]) - h, std::fabs(p[2]) - h});
            c.normal = {0, 1, 0};
            break;
        }
        case ShapeKind::ring:  // sampled and checked in ring_test.cpp, not by these tests
            ADD_FAILURE() << "check_point: the ring's checks are in ring_test.cpp";
            break;
        case ShapeKind::room: {
            const Room& r = s.room;
            const double h = 0.5 * r.size;
            // The six walls, in RoomPart's order (floor, ceiling, left, right, back, front): the axis
            // each is normal to; the even ones lie at -h with normal +axis, the odd ones at +h, -axis.
            constexpr int k_wall_axis[] = {1, 1, 0, 0, 2, 2};
            const int part = room_part_from_color(color);
            switch (part) {
                case k_room_floor:
                case k_room_ceiling:
                case k_room_left_wall:
                case k_room_right_wall:
                case k_room_back_wall:
                case k_room_front_wall: {
                    const int axis = k_wall_axis[part];
                    const double side = part % 2 == 0 ? -1.0 : 1.0;
                    c = box_face_check(p, h, axis, side);
                    c.normal = {0, 0, 0};
                    c.normal[axis] = -side;
                    break;
                }
                case k_room_sphere: {
                    const Vec3 d{p[0] - r.sphere_center[0], p[1] - r.sphere_center[1],
                                 p[2] - r.sphere_center[2]};
                    c.distance = std::fabs(len(d) - r.sphere_radius);
                    c.normal = {d[0] / len(d), d[1] / len(d), d[2] / len(d)};
                    break;
                }
                case k_room_cube: {
                    // Into the cube's frame: undo the turn about y.
                    const double yaw = r.cube_yaw_degrees * k_pi / 180, co = std::cos(yaw),
                                 si = std::sin(yaw);
                    const Vec3 d{p[0] - r.cube_center[0], p[1] - r.cube_center[1], p[2] - r.cube_center[2]};
                    const Vec3 q{co * d[0] - si * d[2], d[1], si * d[0] + co * d[2]};
                    const prt::pool::Float3 nl{float(co * n.x - si * n.z), n.y, float(si * n.x + co * n.z)};
                    c = cube_check(q, 0.5 * r.cube_edge, nl);
                    EXPECT_FALSE(c.normal[1] < -0.5) << "the cube's bottom face is not sampled";
                    c.normal = {co * c.normal[0] + si * c.normal[2], c.normal[1],
                                -si * c.normal[0] + co * c.normal[2]};
                    break;
                }
                default:
                    ADD_FAILURE() << "a room point has a color of no part";
                    break;
            }
            break;
        }
    }
    return c;
}

struct ShapeCase {
    ShapeKind kind;
    Sampling sampling;
};

std::string case_name(const ::testing::TestParamInfo<ShapeCase>& info) {
    return std::string(shape_name(info.param.kind)) + "_" + sampling_name(info.param.sampling);
}

class SynthShapes : public ::testing::TestWithParam<ShapeCase> {};

}  // namespace

TEST_P(SynthShapes, PointsLieOnTheSurfaceWithTrueNormals) {
    const ShapeCase c = GetParam();
    const std::uint64_t n = 20000;
    const SynthResult r = run(c.kind, n, c.sampling);
    const Shape shape = make_shape(c.kind);
    ASSERT_EQ(r.cloud.size(), n);
    ASSERT_EQ(r.cloud.normals.size(), n);
    ASSERT_EQ(r.cloud.colors.size(), n);
    EXPECT_TRUE(r.cloud.flags & prt::pool::k_model_synthetic);
    const double size = shape_size(shape);
    double worst_distance = 0, worst_normal = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const Check k = check_point(shape, r.cloud.positions[i], r.cloud.normals[i], r.cloud.colors[i]);
        worst_distance = std::max(worst_distance, k.distance / size);
        const auto& m = r.cloud.normals[i];
        worst_normal = std::max({worst_normal, std::fabs(m.x - k.normal[0]), std::fabs(m.y - k.normal[1]),
                                 std::fabs(m.z - k.normal[2])});
    }
    EXPECT_LT(worst_distance, 1e-12) << "relative distance to the true surface";
    EXPECT_LT(worst_normal, 1e-6) << "normal component error (float storage)";
}

TEST_P(SynthShapes, UniformByArea) {
    const ShapeCase c = GetParam();
    const std::uint64_t n = 40000;
    const SynthResult r = run(c.kind, n, c.sampling);
    const Shape s = make_shape(c.kind);
    // Chi-square over equal-probability (sphere, plane, cube) or area-weighted (torus) bins; the
    // threshold is the mean plus 6 standard deviations of the chi-square distribution.
    std::vector<double> expected;
    std::vector<double> observed;
    auto bin_index = [&](const Vec3& p, const prt::pool::Float3& nrm) -> std::size_t {
        switch (c.kind) {
            case ShapeKind::sphere: {  // Archimedes: y uniform in [-r, r]; 16 bands x 16 sectors
                const double y = p[1] / s.sphere.radius;
                const double phi = std::atan2(p[2], p[0]) + k_pi;
                return std::min<std::size_t>(15, std::size_t((y + 1) * 8)) * 16 +
                       std::min<std::size_t>(15, std::size_t(phi / (2 * k_pi) * 16));
            }
            case ShapeKind::torus: {  // 32 tube angles x 8 sectors; expected mass per theta bin below
                const double q = std::hypot(p[0], p[2]) - s.torus.major_radius;
                double theta = std::atan2(p[1], q);
                if (theta < 0) theta += 2 * k_pi;
                const double phi = std::atan2(p[2], p[0]) + k_pi;
                return std::min<std::size_t>(31, std::size_t(theta / (2 * k_pi) * 32)) * 8 +
                       std::min<std::size_t>(7, std::size_t(phi / (2 * k_pi) * 8));
            }
            case ShapeKind::cube: {  // 6 faces x 4 x 4 cells
                const float m[3] = {nrm.x, nrm.y, nrm.z};
                int a = 0;
                for (int b = 1; b < 3; ++b)
                    if (std::fabs(m[b]) > std::fabs(m[a])) a = b;
                const int face = 2 * a + (m[a] < 0 ? 1 : 0);
                const double h = 0.5 * s.cube.edge;
                auto cell = [&](double x) {
                    return std::min<std::size_t>(3, std::size_t((x + h) / (2 * h) * 4));
                };
                return std::size_t(face) * 16 + cell(p[(a + 1) % 3]) * 4 + cell(p[(a + 2) % 3]);
            }
            case ShapeKind::plane: {
                const double h = 0.5 * s.plane.size;
                auto cell = [&](double x) {
                    return std::min<std::size_t>(15, std::size_t((x + h) / (2 * h) * 16));
                };
                return cell(p[0]) * 16 + cell(p[2]);
            }
            case ShapeKind::room:
                return std::size_t(room_part_from_color(r.cloud.colors[&p - r.cloud.positions.data()]));
            case ShapeKind::ring:  // ring_test.cpp
                ADD_FAILURE() << "bin_index: the ring's distribution is tested in ring_test.cpp";
                break;
        }
        return 0;
    };
    switch (c.kind) {
        case ShapeKind::sphere:
            expected.assign(256, n / 256.0);
            break;
        case ShapeKind::torus: {
            // Area element r (R + r cos theta): a theta bin holds (dtheta + k (sin b - sin a)) / 2 pi.
            const double k = s.torus.minor_radius / s.torus.major_radius;
            for (int t = 0; t < 32; ++t) {
                const double a = 2 * k_pi * t / 32, b = 2 * k_pi * (t + 1) / 32;
                const double mass = (b - a + k * (std::sin(b) - std::sin(a))) / (2 * k_pi);
                for (int f = 0; f < 8; ++f) expected.push_back(n * mass / 8);
            }
            break;
        }
        case ShapeKind::cube:
            expected.assign(96, n / 96.0);
            break;
        case ShapeKind::plane:
            expected.assign(256, n / 256.0);
            break;
        case ShapeKind::room: {
            const Room& m = s.room;
            const double wall = m.size * m.size;
            const double areas[k_room_part_count] = {wall,
                                                     wall,
                                                     wall,
                                                     wall,
                                                     wall,
                                                     wall,
                                                     4 * k_pi * m.sphere_radius * m.sphere_radius,
                                                     5 * m.cube_edge * m.cube_edge};
            double total = 0;
            for (double a : areas) total += a;
            for (double a : areas) expected.push_back(n * a / total);
            break;
        }
        case ShapeKind::ring:  // ring_test.cpp
            FAIL() << "the ring's distribution is tested in ring_test.cpp";
    }
    observed.assign(expected.size(), 0);
    for (std::size_t i = 0; i < n; ++i) observed.at(bin_index(r.cloud.positions[i], r.cloud.normals[i])) += 1;
    if (c.kind == ShapeKind::room || c.kind == ShapeKind::cube) {
        // Points are apportioned to faces by area: each part within one point per face of exact.
        std::vector<double> per_part(c.kind == ShapeKind::room ? k_room_part_count : 6, 0);
        for (std::size_t b = 0; b < observed.size(); ++b)
            per_part[c.kind == ShapeKind::room ? b : b / 16] += observed[b];
        for (std::size_t p = 0; p < per_part.size(); ++p) {
            double exact = 0;
            for (std::size_t b = 0; b < expected.size(); ++b)
                if ((c.kind == ShapeKind::room ? b : b / 16) == p) exact += expected[b];
            EXPECT_NEAR(per_part[p], exact, c.kind == ShapeKind::room && p == k_room_cube ? 5.0 : 1.0)
                << "part " << p;
        }
    }
    if (c.kind != ShapeKind::room) {
        double chi2 = 0;
        for (std::size_t b = 0; b < expected.size(); ++b)
            chi2 += (observed[b] - expected[b]) * (observed[b] - expected[b]) / expected[b];
        const double dof = double(expected.size() - 1);
        EXPECT_LT(chi2, dof + 6 * std::sqrt(2 * dof)) << "chi-square over " << expected.size() << " bins";
        if (c.sampling == Sampling::r2) {
            EXPECT_LT(chi2, dof) << "low-discrepancy points are more even than random";
        }
    }
    // The part ranges in the result agree with the colors.
    std::uint64_t covered = 0;
    for (const PartRange& part : r.parts) {
        EXPECT_EQ(part.first, covered);
        covered += part.count;
        for (std::uint64_t i = part.first; i < part.first + part.count; ++i) {
            const auto& col = r.cloud.colors[i];
            if (col.r != part.color.r || col.g != part.color.g || col.b != part.color.b) {
                ADD_FAILURE() << "point " << i << " has a color other than its part " << part.name;
                break;
            }
        }
    }
    EXPECT_EQ(covered, n);
}

INSTANTIATE_TEST_SUITE_P(
    AllShapes, SynthShapes,
    ::testing::Values(ShapeCase{ShapeKind::sphere, Sampling::r2},
                      ShapeCase{ShapeKind::sphere, Sampling::random},
                      ShapeCase{ShapeKind::torus, Sampling::r2},
                      ShapeCase{ShapeKind::torus, Sampling::random}, ShapeCase{ShapeKind::cube, Sampling::r2},
                      ShapeCase{ShapeKind::cube, Sampling::random}, ShapeCase{ShapeKind::plane, Sampling::r2},
                      ShapeCase{ShapeKind::plane, Sampling::random}, ShapeCase{ShapeKind::room, Sampling::r2},
                      ShapeCase{ShapeKind::room, Sampling::random}),
    case_name);

TEST(Synth, NoiseIsAlongTheNormalAndBounded) {
    const std::uint64_t n = 20000;
    const double noise = 0.01;
    for (ShapeKind kind : {ShapeKind::sphere, ShapeKind::cube}) {
        const SynthResult r = run(kind, n, Sampling::r2, ColorMode::none, noise, 9);
        const Shape s = make_shape(kind);
        const double sigma = noise * (kind == ShapeKind::sphere ? 2 * s.sphere.radius : s.cube.edge);
        EXPECT_DOUBLE_EQ(r.noise_sigma, sigma);
        double sum = 0, sum2 = 0, worst = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const Vec3& p = r.cloud.positions[i];
            const auto& nn = r.cloud.normals[i];
            double offset;  // signed displacement along the normal
            if (kind == ShapeKind::sphere) {
                offset = std::hypot(p[0], p[1], p[2]) - s.sphere.radius;
                // Radial displacement keeps the normal equal to the direction of p.
                const double l = std::hypot(p[0], p[1], p[2]);
                EXPECT_NEAR(nn.x, p[0] / l, 1e-6);
                EXPECT_NEAR(nn.z, p[2] / l, 1e-6);
            } else {
                const Check k = cube_check(p, 0.5 * s.cube.edge, nn);
                const float m[3] = {nn.x, nn.y, nn.z};
                int a = 0;
                for (int b = 1; b < 3; ++b)
                    if (std::fabs(m[b]) > std::fabs(m[a])) a = b;
                offset = m[a] * p[a] - 0.5 * s.cube.edge;
                EXPECT_NEAR(k.distance, std::fabs(offset), 1e-12) << "only along the face normal";
            }
            sum += offset;
            sum2 += offset * offset;
            worst = std::max(worst, std::fabs(offset));
        }
        EXPECT_LE(worst, k_noise_truncation * sigma * (1 + 1e-12));
        EXPECT_GT(worst, 3 * sigma) << "the noise should reach its tails at 20000 draws";
        const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
        EXPECT_NEAR(mean, 0.0, 4 * sigma / std::sqrt(double(n)));
        EXPECT_NEAR(sd / sigma, 1.0, 0.03);  // a 4-sigma truncation lowers it by 0.1 %
    }
}

TEST(Synth, DeterministicForASeedWhateverTheThreads) {
    for (Sampling sampling : {Sampling::r2, Sampling::random}) {
        const SynthResult a = run(ShapeKind::room, 300001, sampling, ColorMode::parts, 0.002, 42, 1);
        const SynthResult b = run(ShapeKind::room, 300001, sampling, ColorMode::parts, 0.002, 42, 2);
        const SynthResult c = run(ShapeKind::room, 300001, sampling, ColorMode::parts, 0.002, 42, 7);
        EXPECT_TRUE(a.cloud.positions == b.cloud.positions && a.cloud.positions == c.cloud.positions);
        EXPECT_EQ(0,
                  std::memcmp(a.cloud.normals.data(), c.cloud.normals.data(), a.cloud.normals.size() * 12));
        EXPECT_EQ(0, std::memcmp(a.cloud.colors.data(), c.cloud.colors.data(), a.cloud.colors.size() * 4));
        EXPECT_EQ(a.parameters_json, c.parameters_json);
        const SynthResult d = run(ShapeKind::room, 300001, sampling, ColorMode::parts, 0.002, 43, 2);
        std::size_t same = 0;
        for (std::size_t i = 0; i < a.cloud.size(); ++i) same += a.cloud.positions[i] == d.cloud.positions[i];
        EXPECT_LT(same, a.cloud.size() / 1000) << "another seed gives other points";
    }
}

TEST(Synth, ScaleAndOffsetApplyToPositionsOnly) {
    for (ShapeKind kind : {ShapeKind::torus, ShapeKind::room}) {
        SynthOptions o;
        o.shape = make_shape(kind);
        o.count = 5000;
        o.noise = 0.001;
        o.colors = ColorMode::parts;
        const SynthResult a = synthesize(o);
        o.shape.scale = 2.5;
        o.shape.offset = {1e6, -3, 7};
        const SynthResult b = synthesize(o);
        EXPECT_DOUBLE_EQ(b.noise_sigma, 2.5 * a.noise_sigma);
        for (std::size_t i = 0; i < a.cloud.size(); ++i) {
            for (int k = 0; k < 3; ++k)
                ASSERT_NEAR(b.cloud.positions[i][k], a.cloud.positions[i][k] * 2.5 + o.shape.offset[k], 1e-9);
            ASSERT_EQ(a.cloud.normals[i].x, b.cloud.normals[i].x);
            ASSERT_EQ(a.cloud.normals[i].y, b.cloud.normals[i].y);
            ASSERT_EQ(a.cloud.normals[i].z, b.cloud.normals[i].z);
        }
    }
}

TEST(Synth, ExactCountsAndColorModes) {
    for (std::uint64_t n : {1u, 2u, 7u, 13u, 1001u}) {
        const SynthResult r = run(ShapeKind::room, n);
        EXPECT_EQ(r.cloud.size(), n);
        std::uint64_t sum = 0;
        for (const PartRange& p : r.parts) sum += p.count;
        EXPECT_EQ(sum, n);
    }
    EXPECT_FALSE(run(ShapeKind::sphere, 10, Sampling::r2, ColorMode::none).cloud.has_colors());
    const SynthResult normal = run(ShapeKind::plane, 10, Sampling::r2, ColorMode::normal);
    EXPECT_EQ(normal.cloud.colors[3].r, 128);  // n = (0, 1, 0) -> (0.5, 1, 0.5) * 255
    EXPECT_EQ(normal.cloud.colors[3].g, 255);
    SynthOptions o;
    o.shape = make_shape(ShapeKind::cube);
    o.count = 12;
    o.colors = ColorMode::constant;
    o.color = {1, 2, 3, 255};
    const SynthResult constant = synthesize(o);
    for (const auto& c : constant.cloud.colors) EXPECT_TRUE(c.r == 1 && c.g == 2 && c.b == 3 && c.a == 255);
    o.count = 0;
    EXPECT_THROW(synthesize(o), prt::Error);
    o.count = 10;
    o.noise = -0.1;
    EXPECT_THROW(synthesize(o), prt::Error);
}

TEST(Synth, PoolRoundTripWithOriginAtBoundingBoxCentre) {
    SynthOptions o;
    o.shape = make_shape(ShapeKind::room);
    o.shape.offset = {250000.5, -10, 3};
    o.count = 20000;
    o.colors = ColorMode::parts;
    const SynthResult r = synthesize(o);
    prt::pool::PoolWriter w;
    prt::pre::write_point_sections(r.cloud, w);
    w.add_provenance("prt-synth", "test", r.parameters_json);
    const prt::pool::PoolFile pool = prt::pool::PoolFile::from_bytes(w.serialize(), "synth.pool");

    Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    for (const Vec3& p : r.cloud.positions)
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], p[k]);
            hi[k] = std::max(hi[k], p[k]);
        }
    const prt::pool::ModelInfo& info = pool.model_info();
    EXPECT_EQ(info.point_count, o.count);
    EXPECT_TRUE(info.flags & prt::pool::k_model_synthetic);
    for (int k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(info.origin[k], 0.5 * (lo[k] + hi[k]));
    // The room spans the box: the centre is the offset, the half extent size / 2.
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(info.origin[k], o.shape.offset[k], 1e-3);
        EXPECT_NEAR(info.bounds_max[k], 1.0, 1e-3);
    }
    const auto pos = pool.array<prt::pool::Float3>(prt::pool::SectionType::positions);
    const auto nrm = pool.array<prt::pool::Float3>(prt::pool::SectionType::normals);
    const auto col = pool.array<prt::pool::Rgba8>(prt::pool::SectionType::colors);
    ASSERT_EQ(pos.size(), o.count);
    ASSERT_EQ(nrm.size(), o.count);
    ASSERT_EQ(col.size(), o.count);
    for (std::size_t i = 0; i < o.count; ++i) {
        ASSERT_NEAR(pos[i].x, r.cloud.positions[i][0] - info.origin[0], 1e-6);
        ASSERT_NEAR(pos[i].y, r.cloud.positions[i][1] - info.origin[1], 1e-6);
        ASSERT_NEAR(pos[i].z, r.cloud.positions[i][2] - info.origin[2], 1e-6);
        ASSERT_EQ(nrm[i].x, r.cloud.normals[i].x);
        ASSERT_EQ(col[i].g, r.cloud.colors[i].g);
    }
    // The provenance rebuilds the shape, and the stored points lie on it to float precision.
    const Shape s = shape_from_provenance(pool.provenance_json(), pool.label());
    EXPECT_EQ(s.kind, ShapeKind::room);
    EXPECT_EQ(s.offset, o.shape.offset);
    EXPECT_EQ(s.room.cube_center, o.shape.room.cube_center);
    for (std::size_t i = 0; i < o.count; i += 97) {
        const Vec3 p{info.origin[0] + pos[i].x, info.origin[1] + pos[i].y, info.origin[2] + pos[i].z};
        EXPECT_LT(std::fabs(signed_distance(s, p)), 1e-6);
    }
    const auto params = nlohmann::json::parse(pool.provenance_json()).back()["parameters"];
    EXPECT_EQ(params["points"], o.count);
    EXPECT_EQ(params["parts"].size(), std::size_t(k_room_part_count));
    EXPECT_EQ(params["parts"][2]["name"], "left_wall");
}

// ---- The command line ---------------------------------------------------------------------------

namespace {

std::size_t line_count(const std::string& s) {
    return std::count(s.begin(), s.end(), '\n');
}

}  // namespace

TEST(PrtSynthTool, WritesAPool) {
    PRT_NEED_SYNTH();
    ToolDir dir("prt_synth_test_");
    const fs::path out = dir.path() / "t.pool";
    ToolRun r =
        dir.run("torus --major 2 --minor 0.5 -n 5000 --noise 0.001 --offset=1,-2,3 --seed 5 --quiet -o '" +
                out.string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err, "") << "--quiet prints nothing";
    const prt::pool::PoolFile pool = prt::pool::PoolFile::open(out);
    EXPECT_EQ(pool.model_info().point_count, 5000u);
    EXPECT_FALSE(pool.has(prt::pool::SectionType::colors)) << "a torus gets no colors by default";
    const Shape s = shape_from_provenance(pool.provenance_json(), out.string());
    EXPECT_EQ(s.kind, ShapeKind::torus);
    EXPECT_EQ(s.torus.major_radius, 2.0);
    EXPECT_EQ(s.offset, (Vec3{1, -2, 3}));
    const auto params = nlohmann::json::parse(pool.provenance_json()).back()["parameters"];
    EXPECT_EQ(params["seed"], 5);
    EXPECT_DOUBLE_EQ(params["noise_sigma"].get<double>(), 0.001 * 5.0);

    // Without --quiet: a summary on stderr; room gets its part colors.
    r = dir.run("room -n 2000 -o '" + out.string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("prt-synth: wrote"), std::string::npos) << r.err;
    EXPECT_TRUE(prt::pool::PoolFile::open(out).has(prt::pool::SectionType::colors));

    r = dir.run("--help");
    EXPECT_EQ(r.exit_code, 0);
}

TEST(PrtSynthTool, HelpDocumentsEveryOption) {
    PRT_NEED_SYNTH();
    const std::string help = prt::synth_test::expect_help_names(
        {"--output", "--points", "--radius", "--major", "--minor", "--edge", "--size", "--noise", "--scale",
         "--offset", "--seed", "--sampling", "--colors", "--threads", "--quiet"});
    for (const char* shape : {"sphere", "torus", "cube", "plane", "room"})
        EXPECT_NE(help.find(std::string("  ") + shape), std::string::npos) << shape;
}

TEST(PrtSynthTool, BadInputFailsWithoutOutput) {
    PRT_NEED_SYNTH();
    ToolDir dir("prt_synth_test_");
    const fs::path out = dir.path() / "bad.pool";
    const std::string o = " -o '" + out.string() + "'";
    // Usage errors: exit 2 (CLI11's message).
    for (const std::string& args :
         {"sphere --bogus" + o, "blob" + o, std::string("sphere"), "sphere --major 2" + o, "sphere -n 0" + o,
          "sphere --radius abc" + o, "sphere --offset 1,2" + o}) {
        const ToolRun r = dir.run(args);
        EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
        EXPECT_FALSE(r.err.empty()) << args;
        EXPECT_FALSE(fs::exists(out)) << args;
    }
    // Bad values: exit 1, one line naming the problem.
    struct Bad {
        std::string args;
        const char* what;
    };
    for (const Bad& b : {Bad{"sphere --radius -1" + o, "radius"}, Bad{"torus --minor 2" + o, "minor radius"},
                         Bad{"sphere --scale 0" + o, "scale"}, Bad{"sphere --noise 2" + o, "noise"},
                         Bad{"room --size -3" + o, "size"}, Bad{"plane --colors 1,2,300" + o, "--colors"},
                         Bad{"sphere -o /nonexistent-dir/x.pool", "/nonexistent-dir/x.pool"}}) {
        const ToolRun r = dir.run(b.args);
        EXPECT_EQ(r.exit_code, 1) << b.args << "\n" << r.err;
        EXPECT_EQ(line_count(r.err), 1u) << b.args << "\n" << r.err;
        EXPECT_EQ(r.err.rfind("prt-synth: error: ", 0), 0u) << r.err;
        EXPECT_NE(r.err.find(b.what), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(out)) << b.args;
    }
    // Nothing left behind: no temporary files either.
    EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator{}), 1)
        << "only stderr.txt may remain";
}
