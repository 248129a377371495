// prt-synth --scan (scan.h): returns on the surface within the noise bound and exactly on it without
// noise, the scan pattern's angles, outlier counts and displacements, anisotropy on a plane seen
// head-on, incidence limits and dropouts, the room from inside, determinism across thread counts,
// sensors and scan_ids in the pool, and the command line. Ray-surface intersections the checks need
// are written out here (sphere, plane), not taken from first_hit.
#include "scan.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
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
using prt::synth_test::dot;
using prt::synth_test::len;
using prt::synth_test::sub;
using prt::synth_test::ToolDir;
using prt::synth_test::ToolRun;

namespace {

constexpr double k_pi = 3.14159265358979323846;

Shape make_shape(ShapeKind kind) {
    return prt::synth_test::make_shape(kind, {1.0, {1.0, 0.3}, 2.0, 2.0, {1.0, 0.1, 0.5}});
}

/// A coarse scan (fast) of `kind` from the default scanner.
ScanOptions coarse(ShapeKind kind, double sample = 0.15, double line = 0.6) {
    ScanOptions o;
    o.shape = make_shape(kind);
    o.sample_step_degrees = kind == ShapeKind::room ? 4 * sample : sample;
    o.line_step_degrees = kind == ShapeKind::room ? 4 * line : line;
    return o;
}

/// Distance along the ray from s through p to the unit-radius-r sphere at the origin (the nearer
/// root), or -1 when the line misses it. Written out: |s + t d|^2 = r^2.
double sphere_ray(const Vec3& s, const Vec3& p, double r) {
    const Vec3 d0 = sub(p, s);
    const double l = len(d0);
    const Vec3 d{d0[0] / l, d0[1] / l, d0[2] / l};
    const double b = dot(s, d), c = dot(s, s) - r * r, disc = b * b - c;
    if (disc < 0) return -1;
    return -b - std::sqrt(disc);
}

}  // namespace

TEST(Scan, ReturnsLieExactlyOnTheSurfaceWithoutNoise) {
    for (ShapeKind kind : {ShapeKind::sphere, ShapeKind::torus, ShapeKind::cube, ShapeKind::plane,
                           ShapeKind::ring, ShapeKind::room}) {
        const ScanOptions o = coarse(kind);
        const ScanResult r = scan(o);
        const double size = shape_size(o.shape);
        SCOPED_TRACE(shape_name(kind));
        ASSERT_GT(r.returns, 1000u);
        EXPECT_EQ(r.cloud.size(), r.returns);
        EXPECT_FALSE(r.cloud.has_normals()) << "real scans have no normals";
        ASSERT_EQ(r.cloud.intensities.size(), r.cloud.size());
        double worst = 0;
        for (std::size_t i = 0; i < r.cloud.size(); ++i)
            worst = std::max(worst, std::fabs(signed_distance(o.shape, r.cloud.positions[i])));
        EXPECT_LE(worst, 1e-12 * size);
        if (kind == ShapeKind::sphere) {
            // Independently: |p| = 1, and every return faces its scanner.
            const Vec3 s = default_scanners(o.shape, 1)[0];
            for (const Vec3& p : r.cloud.positions) {
                EXPECT_NEAR(len(p), 1.0, 1e-14);
                EXPECT_GT(dot(p, sub(s, p)), 0);
            }
        }
        for (float v : r.cloud.intensities) {
            EXPECT_GE(v, 0.0f);
            EXPECT_LE(v, 1.1f);
        }
    }
    // Placed far from the origin at two scales: on the surface to the rounding of the coordinates.
    for (double scale : {1e-3, 1e4}) {
        ScanOptions o = coarse(ShapeKind::torus);
        o.shape.scale = scale;
        o.shape.offset = {1e6, -1e6, 1e6};
        const ScanResult r = scan(o);
        const double ulp = std::nextafter(1e6 + 10 * scale, INFINITY) - (1e6 + 10 * scale);
        ASSERT_GT(r.returns, 1000u);
        double worst = 0;
        for (const Vec3& p : r.cloud.positions)
            worst = std::max(worst, std::fabs(signed_distance(o.shape, p)));
        EXPECT_LE(worst, 1e-12 * shape_size(o.shape) + 8 * ulp) << scale;
    }
}

TEST(Scan, RaysFollowTheScanPatternAndNoiseStaysOnThem) {
    // Every return lies on a ray of the grid: azimuth k x line step, elevation j x sample step about
    // the scan axis (+y: azimuth 0 along +z, 90 along +x), however far the range noise moved it.
    ScanOptions o = coarse(ShapeKind::sphere);
    o.range_noise = 0.002;
    o.range_noise_per_range = 1e-3;
    const ScanResult r = scan(o);
    const Vec3 s = default_scanners(o.shape, 1)[0];
    const double size = shape_size(o.shape);
    double sum = 0, sum2 = 0, worst_sigmas = 0;
    for (const Vec3& p : r.cloud.positions) {
        const Vec3 d = sub(p, s);
        const double az = std::atan2(d[0], d[2]) * 180 / k_pi;
        const double el = std::asin(d[1] / len(d)) * 180 / k_pi;
        EXPECT_NEAR(az / o.line_step_degrees, std::round(az / o.line_step_degrees), 1e-8);
        EXPECT_NEAR(el / o.sample_step_degrees, std::round(el / o.sample_step_degrees), 1e-8);
        const double t = sphere_ray(s, p, 1.0);
        ASSERT_GT(t, 0);
        const double sigma = o.range_noise * size + o.range_noise_per_range * t;
        const double e = (len(d) - t) / sigma;  // along the ray, in sigmas
        worst_sigmas = std::max(worst_sigmas, std::fabs(e));
        sum += e;
        sum2 += e * e;
    }
    const double n = double(r.cloud.size());
    EXPECT_LE(worst_sigmas, k_noise_truncation + 1e-6) << "truncated like --noise";
    EXPECT_GT(worst_sigmas, 3.0) << "the noise is there";
    EXPECT_NEAR(sum / n, 0.0, 0.02);
    EXPECT_NEAR(std::sqrt(sum2 / n), 1.0, 0.02);  // a 4-sigma truncated normal: 0.9993
    EXPECT_DOUBLE_EQ(r.range_sigma, 0.002 * 2.0);
}

TEST(Scan, OutliersAreCountedAndDisplacedAsAsked) {
    ScanOptions o = coarse(ShapeKind::sphere);
    o.outliers = 0.02;
    o.uniform_outliers = 0.01;
    const ScanResult r = scan(o);
    const std::uint64_t n = r.returns;
    const double size = shape_size(o.shape);
    ASSERT_EQ(r.outlier_indices.size(), std::size_t(std::llround(0.02 * double(n))));
    EXPECT_EQ(r.uniform_count, std::uint64_t(std::llround(0.01 * double(n))));
    EXPECT_EQ(r.uniform_first, n);
    EXPECT_EQ(r.cloud.size(), n + r.uniform_count);
    EXPECT_TRUE(std::is_sorted(r.outlier_indices.begin(), r.outlier_indices.end()));
    EXPECT_EQ(std::adjacent_find(r.outlier_indices.begin(), r.outlier_indices.end()),
              r.outlier_indices.end());
    const Vec3 s = default_scanners(o.shape, 1)[0];
    std::vector<bool> is_outlier(n, false);
    int farther = 0, closer = 0;
    for (std::uint64_t idx : r.outlier_indices) {
        ASSERT_LT(idx, n);
        is_outlier[idx] = true;
        const Vec3& p = r.cloud.positions[idx];
        const double t = sphere_ray(s, p, 1.0);  // the surface this ray hit
        ASSERT_GT(t, 0);
        const double shift = len(sub(p, s)) - t;
        if (shift > 0) {
            ++farther;
            EXPECT_GE(shift, 0.05 * size - 1e-12);
            EXPECT_LE(shift, 0.25 * size + 1e-12);
        } else {
            ++closer;
            EXPECT_GE(-shift, std::min(0.05 * size, 0.9 * t) - 1e-12);
            EXPECT_LE(-shift, 0.25 * size + 1e-12);
            EXPECT_GE(len(sub(p, s)), 0.1 * t - 1e-12);
        }
    }
    const int k = int(r.outlier_indices.size());
    EXPECT_GT(farther, k / 3);
    EXPECT_GT(closer, k / 3);
    for (std::uint64_t i = 0; i < n; ++i)
        if (!is_outlier[i]) {
            ASSERT_LE(std::fabs(len(r.cloud.positions[i]) - 1.0), 1e-14) << i;
        }
    // Uniform outliers: in the bounding box grown by 10 % of the size, spread over it.
    double max_radius = 0;
    for (std::uint64_t i = n; i < r.cloud.size(); ++i) {
        for (int a = 0; a < 3; ++a) EXPECT_LE(std::fabs(r.cloud.positions[i][a]), 1.0 + 0.1 * size);
        max_radius = std::max(max_radius, len(r.cloud.positions[i]));
        EXPECT_EQ(r.part[i], -1);
    }
    EXPECT_GT(max_radius, 1.5);
    // The provenance lists the same indices and counts.
    const auto j = nlohmann::json::parse(r.parameters_json);
    EXPECT_EQ(j["outliers"]["count"].get<std::uint64_t>(), r.outlier_indices.size());
    EXPECT_EQ(j["outliers"]["indices"].get<std::vector<std::uint64_t>>(), r.outlier_indices);
    EXPECT_EQ(j["uniform_outliers"]["count"].get<std::uint64_t>(), r.uniform_count);
    EXPECT_EQ(j["points"].get<std::uint64_t>(), r.cloud.size());
    EXPECT_EQ(j["returns"].get<std::uint64_t>(), n);
}

TEST(Scan, AnisotropyOnAPlaneSeenHeadOn) {
    // The plane y = 0 from 3 above, the head turning about z: scan lines run along z (sample step
    // apart), lines are line step apart along x. Near the foot of the scanner both spacings are the
    // range times the step in radians (to 1/cos^2 < 0.3 %).
    ScanOptions o;
    o.shape = make_shape(ShapeKind::plane);
    o.scanners = {{0, 3, 0}};
    o.axis = {0, 0, 1};
    o.sample_step_degrees = 0.05;
    o.line_step_degrees = 0.2;
    const ScanResult r = scan(o);
    std::vector<Vec3> c;
    for (const Vec3& p : r.cloud.positions)
        if (std::fabs(p[0]) < 0.15 && std::fabs(p[2]) < 0.15) c.push_back(p);
    ASSERT_GT(c.size(), 1000u);
    std::vector<double> along, across;
    for (std::size_t i = 0; i < c.size(); ++i) {
        if (std::fabs(c[i][0]) > 0.12 || std::fabs(c[i][2]) > 0.12) continue;  // full neighbourhoods
        double best_along = INFINITY, best_across = INFINITY;
        for (std::size_t k = 0; k < c.size(); ++k) {
            if (k == i) continue;
            const double dx = c[k][0] - c[i][0], dz = c[k][2] - c[i][2], d = std::hypot(dx, dz);
            (std::fabs(dz) >= std::fabs(dx) ? best_along : best_across) =
                std::min(std::fabs(dz) >= std::fabs(dx) ? best_along : best_across, d);
        }
        along.push_back(best_along);
        across.push_back(best_across);
    }
    auto median = [](std::vector<double> v) {
        std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
        return v[v.size() / 2];
    };
    const double a = median(along), x = median(across);
    EXPECT_NEAR(a, 3 * 0.05 * k_pi / 180, 0.005 * a);
    EXPECT_NEAR(x, 3 * 0.2 * k_pi / 180, 0.005 * x);
    EXPECT_NEAR(x / a, 4.0, 0.04) << "the requested anisotropy";
}

TEST(Scan, NoReturnBeyondTheMaxIncidenceAndDropoutsRiseWithIt) {
    ScanOptions o = coarse(ShapeKind::sphere);
    o.max_incidence_degrees = 60;
    const ScanResult limited = scan(o);
    o.max_incidence_degrees = 90;
    const ScanResult all = scan(o);
    const Vec3 s = default_scanners(o.shape, 1)[0];
    auto incidence = [&](const Vec3& p) {  // the sphere's normal is p
        const Vec3 v = sub(s, p);
        return std::acos(std::clamp(dot(p, v) / (len(p) * len(v)), -1.0, 1.0)) * 180 / k_pi;
    };
    double worst = 0;
    for (const Vec3& p : limited.cloud.positions) worst = std::max(worst, incidence(p));
    EXPECT_LE(worst, 60 + 1e-9);
    EXPECT_GT(worst, 59.0);
    std::uint64_t beyond = 0;
    for (const Vec3& p : all.cloud.positions) beyond += incidence(p) > 60;
    EXPECT_GT(beyond, 1000u);
    EXPECT_EQ(limited.scanners[0].dropped_grazing, beyond + all.scanners[0].dropped_grazing);
    EXPECT_EQ(limited.returns + beyond, all.returns);

    // Dropouts: per incidence band, the kept fraction is 1 - dropout ((1 - cos i) / (1 - cos 85))^2.
    o = coarse(ShapeKind::sphere, 0.08, 0.3);
    const ScanResult base = scan(o);
    o.dropout = 1.0;
    const ScanResult dropped = scan(o);
    EXPECT_EQ(base.returns, dropped.returns + dropped.scanners[0].dropped_dropout);
    const double bands[] = {0, 30, 50, 65, 75, 85};
    for (int b = 0; b + 1 < 6; ++b) {
        double expected = 0, count = 0, kept = 0;
        for (const Vec3& p : base.cloud.positions) {
            const double i = incidence(p);
            if (i < bands[b] || i >= bands[b + 1]) continue;
            const double x = (1 - std::cos(i * k_pi / 180)) / (1 - std::cos(85 * k_pi / 180));
            expected += 1 - x * x;
            ++count;
        }
        for (const Vec3& p : dropped.cloud.positions) {
            const double i = incidence(p);
            kept += i >= bands[b] && i < bands[b + 1];
        }
        ASSERT_GT(count, 500) << bands[b];
        EXPECT_NEAR(kept / count, expected / count, 4 * std::sqrt(0.25 / count) + 0.005) << bands[b];
    }
}

TEST(Scan, TheRoomFromInsideSeesEveryPart) {
    ScanOptions o = coarse(ShapeKind::room);
    o.colors = ColorMode::parts;
    const ScanResult r = scan(o);
    ASSERT_EQ(r.scanners.size(), 1u);
    EXPECT_TRUE(r.scanners[0].full_field);
    EXPECT_EQ(r.scanners[0].misses, 0u) << "a closed room";
    const Vec3 s = default_scanners(o.shape, 1)[0];
    std::vector<std::uint64_t> count(k_room_part_count, 0);
    for (std::size_t i = 0; i < r.cloud.size(); ++i) {
        const int part = r.part[i];
        ASSERT_GE(part, 0);
        ASSERT_LT(part, k_room_part_count);
        ++count[part];
        EXPECT_EQ(room_part_from_color(r.cloud.colors[i]), part);
        // On that part (within rounding): its own surface, not just any.
        const Vec3& p = r.cloud.positions[i];
        const Room& room = o.shape.room;
        double d = 0;
        switch (part) {
            case k_room_floor:
                d = p[1] + 1;
                break;
            case k_room_ceiling:
                d = p[1] - 1;
                break;
            case k_room_left_wall:
                d = p[0] + 1;
                break;
            case k_room_right_wall:
                d = p[0] - 1;
                break;
            case k_room_back_wall:
                d = p[2] + 1;
                break;
            case k_room_front_wall:
                d = p[2] - 1;
                break;
            case k_room_sphere:
                d = len(sub(p, room.sphere_center)) - room.sphere_radius;
                break;
            default:
                d = signed_distance(o.shape, p);
        }
        EXPECT_LE(std::fabs(d), 1e-12) << room_part_name(part);
        // Nothing below the blind cone.
        const Vec3 v = sub(p, s);
        EXPECT_GE(std::asin(v[1] / len(v)) * 180 / k_pi, -60 - 1e-9);
    }
    const auto j = nlohmann::json::parse(r.parameters_json);
    ASSERT_EQ(j["parts"].size(), std::size_t(k_room_part_count));
    for (int p = 0; p < k_room_part_count; ++p) {
        EXPECT_GT(count[p], 100u) << room_part_name(p);
        EXPECT_EQ(j["parts"][p]["name"], room_part_name(p));
        EXPECT_EQ(j["parts"][p]["returns"].get<std::uint64_t>(), count[p]) << room_part_name(p);
    }
    // The sphere and the cube cast shadows on the floor: part of the floor is hidden.
    EXPECT_LT(count[k_room_floor], count[k_room_ceiling]);
}

TEST(Scan, DeterministicForASeedWhateverTheThreads) {
    ScanOptions o = coarse(ShapeKind::room);
    o.scanners = default_scanners(o.shape, 2);
    o.range_noise = 0.001;
    o.dropout = 0.5;
    o.outliers = 0.01;
    o.uniform_outliers = 0.005;
    o.colors = ColorMode::normal;
    o.normals = true;
    o.seed = 9;
    o.threads = 1;
    const ScanResult a = scan(o);
    for (unsigned t : {2u, 5u}) {
        o.threads = t;
        const ScanResult b = scan(o);
        EXPECT_EQ(a.cloud.positions, b.cloud.positions) << t;
        EXPECT_EQ(a.cloud.intensities, b.cloud.intensities) << t;
        EXPECT_EQ(a.cloud.scan_ids, b.cloud.scan_ids) << t;
        EXPECT_EQ(a.outlier_indices, b.outlier_indices) << t;
        EXPECT_EQ(a.parameters_json, b.parameters_json) << t;
        ASSERT_EQ(a.cloud.normals.size(), b.cloud.normals.size());
        for (std::size_t i = 0; i < a.cloud.normals.size(); ++i)
            ASSERT_TRUE(a.cloud.normals[i].x == b.cloud.normals[i].x &&
                        a.cloud.normals[i].y == b.cloud.normals[i].y &&
                        a.cloud.normals[i].z == b.cloud.normals[i].z);
    }
    o.seed = 10;
    const ScanResult c = scan(o);
    EXPECT_NE(a.cloud.positions, c.cloud.positions) << "another seed, other noise";
}

TEST(Scan, SeveralScannersAndTheirFields) {
    // Three scanners around a torus: each scanner's returns face it; scan ids follow the order.
    ScanOptions o = coarse(ShapeKind::torus);
    o.scanners = default_scanners(o.shape, 3);
    const ScanResult r = scan(o);
    ASSERT_EQ(r.cloud.sensors.size(), 3u);
    ASSERT_EQ(r.cloud.scan_ids.size(), r.cloud.size());
    std::uint64_t total = 0;
    for (std::uint32_t s = 0; s < 3; ++s) {
        const ScannerStats& st = r.scanners[s];
        EXPECT_EQ(r.cloud.sensors[s].kind, prt::pool::k_sensor_point);
        for (int a = 0; a < 3; ++a) EXPECT_EQ(r.cloud.sensors[s].position[a], o.scanners[s][a]);
        EXPECT_NEAR(len(sub(o.scanners[s], {0, 0, 0})), 3 * shape_size(o.shape), 1e-12);
        EXPECT_FALSE(st.full_field);
        EXPECT_GT(st.returns, 1000u);
        EXPECT_EQ(st.first, total);
        for (std::uint64_t i = st.first; i < st.first + st.returns; ++i) {
            ASSERT_EQ(r.cloud.scan_ids[i], s);
            // The true normal faces the scanner (first hits are seen from the front).
            const Vec3 n = closest(o.shape, r.cloud.positions[i]).normal;
            ASSERT_GT(dot(n, sub(o.scanners[s], r.cloud.positions[i])), 0);
        }
        total += st.returns;
        EXPECT_EQ(st.rays, st.misses + st.dropped_grazing + st.dropped_dropout + st.returns);
    }
    EXPECT_EQ(total, r.cloud.size());
    // From inside the ring's hole: the whole sphere but the blind cone, only the inner wall.
    ScanOptions in = coarse(ShapeKind::ring, 0.5, 1.0);
    in.scanners = {{0.1, 0.05, -0.2}};
    const ScanResult ri = scan(in);
    EXPECT_TRUE(ri.scanners[0].full_field);
    ASSERT_GT(ri.returns, 100u);
    for (std::int8_t p : ri.part) EXPECT_EQ(p, k_ring_inner);
}

TEST(Scan, InvalidOptionsThrow) {
    auto bad = [](const std::function<void(ScanOptions&)>& change, const char* what) {
        ScanOptions o = coarse(ShapeKind::sphere);
        change(o);
        try {
            scan(o);
            ADD_FAILURE() << "no error for " << what;
        } catch (const prt::Error& e) {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    bad([](ScanOptions& o) { o.scanners = {{0.2, 0, 0}}; }, "inside the sphere");
    bad([](ScanOptions& o) { o.scanners = {{1, 0, 0}}; }, "on the surface");
    bad([](ScanOptions& o) { o.sample_step_degrees = 0; }, "--sample-step");
    bad([](ScanOptions& o) { o.line_step_degrees = NAN; }, "--line-step");
    bad([](ScanOptions& o) { o.max_incidence_degrees = 91; }, "--max-incidence");
    bad([](ScanOptions& o) { o.axis = {0, 0, 0}; }, "--scan-axis");
    bad([](ScanOptions& o) { o.outliers = -0.1; }, "--outliers");
    bad([](ScanOptions& o) { o.scanners = {{NAN, 5, 5}}; }, "--scanner");
    bad([](ScanOptions& o) { o.sample_step_degrees = o.line_step_degrees = 1e-4; }, "more than");
    bad([](ScanOptions& o) { o.scanners = {{0, 0.3, 50}}, o.max_incidence_degrees = 1e-6; }, "no returns");
    bad(
        [](ScanOptions& o) {
            o.shape = make_shape(ShapeKind::room);
            o.scanners = {{0, 0, 3}};
        },
        "outside the air of the room");
}

// ---- The command line ---------------------------------------------------------------------------

TEST(PrtSynthScanTool, WritesSensorsScanIdsAndProvenance) {
    PRT_NEED_SYNTH();
    ToolDir dir("prt_synth_scan_test_");
    const fs::path out = dir.path() / "scan.pool";
    ToolRun r = dir.run(
        "sphere --scan --scanner 6,1,0 --scanner -6,1,0 --scanner 0,1,6 --sample-step 0.2 "
        "--line-step 0.5 --range-noise 0.001 --outliers 0.01 --seed 3 -o '" +
        out.string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("returns"), std::string::npos) << "counts reported: " << r.err;
    EXPECT_NE(r.err.find("prt-synth: wrote"), std::string::npos) << r.err;
    {
        const prt::pool::PoolFile pool = prt::pool::PoolFile::open(out);
        const prt::pre::PointCloud c = prt::pre::read_point_sections(pool);
        ASSERT_EQ(c.sensors.size(), 3u);
        const Vec3 expected[3] = {{6, 1, 0}, {-6, 1, 0}, {0, 1, 6}};
        for (int s = 0; s < 3; ++s) {
            EXPECT_EQ(c.sensors[s].kind, prt::pool::k_sensor_point);
            for (int a = 0; a < 3; ++a) EXPECT_EQ(c.sensors[s].position[a], expected[s][a]);
        }
        ASSERT_EQ(c.scan_ids.size(), c.size());
        ASSERT_EQ(c.intensities.size(), c.size());
        EXPECT_FALSE(c.has_normals());
        const auto j = nlohmann::json::parse(pool.provenance_json()).back()["parameters"];
        EXPECT_EQ(j["mode"], "scan");
        EXPECT_EQ(j["points"].get<std::uint64_t>(), c.size());
        EXPECT_EQ(j["scanners"].size(), 3u);
        EXPECT_DOUBLE_EQ(j["pattern"]["anisotropy"].get<double>(), 2.5);
        std::uint64_t outliers = 0;
        for (std::size_t i = 0; i < c.size(); ++i) {
            ASSERT_LT(c.scan_ids[i], 3);
            // Points (float in the pool) face their scanner, off the unit sphere only by noise
            // (4 sigma = 0.008) unless displaced outliers.
            const Vec3& p = c.positions[i];
            if (std::fabs(len(p) - 1) > 0.0081) {
                ++outliers;
                continue;
            }
            EXPECT_GT(dot(p, sub(expected[c.scan_ids[i]], p)), -0.01);
        }
        EXPECT_EQ(outliers, j["outliers"]["count"].get<std::uint64_t>());
        // A later tool appends its own entry: the shape is still found.
        prt::pool::PoolWriter w;
        w.carry_over(pool);
        w.add_provenance("prt-radii", "test", R"({"k": 8})");
        w.write(dir.path() / "later.pool");
    }
    const prt::pool::PoolFile later = prt::pool::PoolFile::open(dir.path() / "later.pool");
    EXPECT_EQ(nlohmann::json::parse(later.provenance_json()).back()["tool"], "prt-radii");
    const Shape s = shape_from_provenance(later.provenance_json(), "later.pool");
    EXPECT_EQ(s.kind, ShapeKind::sphere);
    EXPECT_EQ(s.sphere.radius, 1.0);

    // One default scanner: a sensor, no scan ids; --scan-normals writes the true normals.
    r = dir.run("torus --scan --scan-normals --quiet -o '" + out.string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err, "");
    const prt::pre::PointCloud c = prt::pre::read_point_sections(prt::pool::PoolFile::open(out));
    EXPECT_EQ(c.sensors.size(), 1u);
    EXPECT_FALSE(c.has_scan_ids());
    ASSERT_TRUE(c.has_normals());
    const Shape torus = make_shape(ShapeKind::torus);
    for (std::size_t i = 0; i < c.size(); i += 97) {
        const Vec3 n = closest(shape_from_provenance(prt::pool::PoolFile::open(out).provenance_json(), "t"),
                               c.positions[i])
                           .normal;
        EXPECT_NEAR(n[0] * c.normals[i].x + n[1] * c.normals[i].y + n[2] * c.normals[i].z, 1.0, 1e-5);
    }
    (void)torus;
    r = dir.run("cube --scan --scanners 4 --quiet -o '" + out.string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(prt::pre::read_point_sections(prt::pool::PoolFile::open(out)).sensors.size(), 4u);
}

TEST(PrtSynthScanTool, HelpDocumentsEveryScanOption) {
    PRT_NEED_SYNTH();
    prt::synth_test::expect_help_names({"--scan ", "--scanner ", "--scanners", "--scan-axis", "--sample-step",
                                        "--line-step", "--blind-cone", "--max-incidence", "--dropout",
                                        "--range-noise ", "--range-noise-per-range", "--outliers",
                                        "--uniform-outliers", "--intensity-noise", "--scan-normals",
                                        "0.025 (room: 0.2)", "4 x --sample-step"});
}

TEST(PrtSynthScanTool, BadOptionsFailWithOneLine) {
    PRT_NEED_SYNTH();
    ToolDir dir("prt_synth_scan_test_");
    const fs::path out = dir.path() / "bad.pool";
    const std::string o = " -o '" + out.string() + "'";
    struct Bad {
        std::string args;
        int code;
        const char* what;
    };
    for (const Bad& b : {
             Bad{"sphere --scan -n 5" + o, 2, "--points"},
             Bad{"sphere --scan --noise 0.1" + o, 2, "--noise"},
             Bad{"sphere --scan --sampling random" + o, 2, "--sampling"},
             Bad{"sphere --sample-step 0.1" + o, 2, "--scan only"},
             Bad{"sphere --outliers 0.1" + o, 2, "--scan only"},
             Bad{"sphere --scan --scanner 5,0,0 --scanners 2" + o, 2, "--scanners"},
             Bad{"sphere --scan --scanners 0" + o, 2, "--scanners"},
             Bad{"sphere --scan --scan-axis 1,2" + o, 2, "--scan-axis"},
             Bad{"sphere --scan --scanner 0,0,0" + o, 1, "inside the sphere"},
             Bad{"torus --scan --scanner 1,0,0" + o, 1, "inside the torus"},
             Bad{"room --scan --scanner 0,0,5" + o, 1, "outside the air of the room"},
             Bad{"room --scan --scanner 0,-1,0" + o, 1, "on the surface of the room"},
             Bad{"room --scan --scanner -0.4,-0.6,-0.2" + o, 1, "inside the sphere of the room"},
             Bad{"room --scan --scanner 0.44,-0.7,0.24" + o, 1, "inside the cube of the room"},
             Bad{"plane --scan --scanner 0,0,0" + o, 1, "on the surface of the plane"},
             Bad{"sphere --scan --sample-step 0" + o, 1, "--sample-step"},
             Bad{"sphere --scan --line-step nan" + o, 1, "--line-step"},
             Bad{"sphere --scan --scanner 1,nan,3" + o, 1, "--scanner"},
             Bad{"sphere --scan --scanner 1,2" + o, 1, "--scanner"},
             Bad{"sphere --scan --scanner 1,2,3,4" + o, 1, "--scanner"},
             Bad{"sphere --scan --max-incidence 95" + o, 1, "--max-incidence"},
             Bad{"sphere --scan --blind-cone 90" + o, 1, "--blind-cone"},
             Bad{"sphere --scan --outliers 1.5" + o, 1, "--outliers"},
             Bad{"sphere --scan --range-noise -1" + o, 1, "--range-noise"},
             Bad{"sphere --scan --scan-axis 0,0,0" + o, 1, "--scan-axis"},
             Bad{"sphere --scan --sample-step 1e-5 --line-step 1e-5" + o, 1, "rays"},
             Bad{"sphere --scan --sample-step 10 --line-step 1e-7" + o, 1, "scan lines"},
             Bad{"sphere --scan -o /nonexistent-dir/x.pool", 1, "/nonexistent-dir/x.pool"},
         }) {
        const ToolRun r = dir.run(b.args);
        EXPECT_EQ(r.exit_code, b.code) << b.args << "\n" << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << b.args << "\n" << r.err;
        EXPECT_EQ(r.err.rfind("prt-synth: error: ", 0), 0u) << r.err;
        EXPECT_NE(r.err.find(b.what), std::string::npos) << b.args << "\n" << r.err;
        EXPECT_FALSE(fs::exists(out)) << b.args;
    }
    EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator{}), 1)
        << "only stderr.txt may remain";
}
