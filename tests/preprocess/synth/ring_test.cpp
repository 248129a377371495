// prt-synth's ring (the mirror band of thesis Fig. 5.3a): points on the band's three sampled
// surfaces with their true normals (checked against the band's equations written out here, not
// analytic.cpp's code), counts in proportion to the areas, closest() against brute force, the
// provenance round trip and the command line.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "analytic.h"
#include "prt/formats/pool.h"
#include "synth.h"

using namespace prt::synth;

namespace {

constexpr double k_pi = 3.14159265358979323846;

Shape ring_shape() {
    Shape s;
    s.kind = ShapeKind::ring;
    s.ring = {0.8, 0.05, 0.3};
    return s;
}

}  // namespace

TEST(Ring, PointsLieOnTheBandWithTrueNormals) {
    SynthOptions o;
    o.shape = ring_shape();
    o.count = 20000;
    const SynthResult r = synthesize(o);
    ASSERT_EQ(r.parts.size(), 3u);
    const double R = 0.8, t = 0.05, h = 0.3, outer = R + t;
    const double areas[3] = {2 * k_pi * R * h, 2 * k_pi * outer * h, k_pi * (outer * outer - R * R)};
    const double total = areas[0] + areas[1] + areas[2];
    for (int p = 0; p < 3; ++p) {
        EXPECT_NEAR(double(r.parts[p].count), 20000 * areas[p] / total, 1.0) << r.parts[p].name;
        for (std::uint64_t i = r.parts[p].first; i < r.parts[p].first + r.parts[p].count; ++i) {
            const auto& q = r.cloud.positions[i];
            const auto& n = r.cloud.normals[i];
            const double rho = std::hypot(q[0], q[2]);
            if (p == k_ring_top) {
                ASSERT_NEAR(q[1], h / 2, 1e-12);
                ASSERT_GE(rho, R - 1e-12);
                ASSERT_LE(rho, outer + 1e-12);
                ASSERT_NEAR(n.y, 1.0f, 1e-6f);
            } else {
                const double want = p == k_ring_inner ? R : outer, sign = p == k_ring_inner ? -1.0 : 1.0;
                ASSERT_NEAR(rho, want, 1e-9);
                ASSERT_LE(std::fabs(q[1]), h / 2 + 1e-12);
                ASSERT_NEAR(n.x, sign * q[0] / rho, 1e-6);
                ASSERT_NEAR(n.z, sign * q[2] / rho, 1e-6);
                ASSERT_NEAR(n.y, 0.0f, 1e-6f);
            }
            const SurfacePoint c = closest(o.shape, q);
            ASSERT_NEAR(c.signed_distance, 0.0, 1e-9);
            ASSERT_EQ(c.part, p);
        }
    }
}

TEST(Ring, ClosestMatchesBruteForce) {
    // Dense samples of the band's closed boundary in the (rho, y) half-plane, turned about y.
    const Shape s = ring_shape();
    const double R = 0.8, t = 0.05, h = 0.3;
    std::uint64_t seed = 7;
    auto rnd = [&]() {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        return double(seed >> 11) / double(1ull << 53);
    };
    for (int k = 0; k < 200; ++k) {
        const Vec3 p{2.4 * rnd() - 1.2, 0.8 * rnd() - 0.4, 2.4 * rnd() - 1.2};
        const double rho = std::hypot(p[0], p[2]);
        double best = 1e30;
        const int steps = 4000;
        for (int i = 0; i <= steps; ++i) {
            const double u = double(i) / steps;
            const double pts[4][2] = {
                {R, -h / 2 + u * h}, {R + t, -h / 2 + u * h}, {R + u * t, h / 2}, {R + u * t, -h / 2}};
            for (const auto& b : pts) best = std::min(best, std::hypot(rho - b[0], p[1] - b[1]));
        }
        const bool inside = rho > R && rho < R + t && std::fabs(p[1]) < h / 2;
        const SurfacePoint c = closest(s, p);
        EXPECT_NEAR(std::fabs(c.signed_distance), best, 1e-4) << k;
        EXPECT_EQ(c.signed_distance < 0, inside) << k;
        const double d = std::hypot(c.point[0] - p[0], c.point[1] - p[1], c.point[2] - p[2]);
        EXPECT_NEAR(d, std::fabs(c.signed_distance), 1e-9);
    }
}

TEST(Ring, ProvenanceRebuildsTheShape) {
    Shape s = ring_shape();
    s.scale = 2;
    s.offset = {1, 2, 3};
    const Shape back = shape_from_json(shape_to_json(s), "test");
    EXPECT_EQ(back.kind, ShapeKind::ring);
    EXPECT_EQ(back.ring.radius, s.ring.radius);
    EXPECT_EQ(back.ring.thickness, s.ring.thickness);
    EXPECT_EQ(back.ring.height, s.ring.height);
    Shape bad = ring_shape();
    bad.ring.height = 0;
    EXPECT_THROW(validate(bad), prt::Error);
}

TEST(Ring, ToolWritesARing) {
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() / ("prt_synth_ring_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const std::string pool = (dir / "ring.pool").string();
    const std::string cmd = std::string(PRT_BIN_DIR) +
                            "/prt-synth ring --radius 0.5 --thickness 0.02 --height 0.2 -n 5000 -o " + pool +
                            " --quiet";
    ASSERT_EQ(std::system(cmd.c_str()), 0);
    const prt::pool::PoolFile f = prt::pool::PoolFile::open(pool);
    EXPECT_EQ(f.model_info().point_count, 5000u);
    EXPECT_NE(f.provenance_json().find("\"kind\":\"ring\""), std::string::npos);
    // --height does not apply to a sphere: a usage error.
    const std::string bad =
        std::string(PRT_BIN_DIR) + "/prt-synth sphere --height 0.2 -o " + pool + " --quiet 2>/dev/null";
    EXPECT_EQ(WEXITSTATUS(std::system(bad.c_str())), 2);
}
