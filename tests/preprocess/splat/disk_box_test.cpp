// The exact disk/box test (preprocess/splat/disk_box.h) against analytic cases, an independent
// polygon-based reference and dense sampling of the disk.
#include "disk_box.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "disk_box_reference.h"

namespace {

using prt::pre::disk_overlaps_box;
using prt::pre::plane_box_distance_sq;

const double k_lo[3] = {0, 0, 0};
const double k_hi[3] = {1, 1, 1};

TEST(DiskBox, AnalyticCases) {
    {  // disk lying on the top face
        const double c[3] = {0.5, 0.5, 1.0}, n[3] = {0, 0, 1};
        EXPECT_TRUE(disk_overlaps_box(c, n, 0.1, k_lo, k_hi));
        EXPECT_DOUBLE_EQ(plane_box_distance_sq(c, n, k_lo, k_hi), 0.0);
    }
    {  // horizontal disk beside the box: distance to the face is exactly 1 (closed sets touch)
        const double c[3] = {2, 0.5, 0.5}, n[3] = {0, 0, 1};
        EXPECT_DOUBLE_EQ(plane_box_distance_sq(c, n, k_lo, k_hi), 1.0);
        EXPECT_TRUE(disk_overlaps_box(c, n, 1.0, k_lo, k_hi));
        EXPECT_FALSE(disk_overlaps_box(c, n, 0.999, k_lo, k_hi));
    }
    {  // a vertical disk facing the box (normal along x): the plane x = 2 misses the box
        const double c[3] = {2, 0.5, 0.5}, n[3] = {1, 0, 0};
        EXPECT_LT(plane_box_distance_sq(c, n, k_lo, k_hi), 0.0);
        EXPECT_FALSE(disk_overlaps_box(c, n, 100.0, k_lo, k_hi));
    }
    {  // plane x + y + z = 3 touches the box only at the corner (1,1,1)
        const double s = 1 / std::sqrt(3.0);
        const double c[3] = {1.5, 1.5, 0}, n[3] = {s, s, s};
        const double d = std::sqrt(1.5);  // |(1,1,1) - c|
        EXPECT_NEAR(std::sqrt(plane_box_distance_sq(c, n, k_lo, k_hi)), d, 1e-12);
        EXPECT_TRUE(disk_overlaps_box(c, n, d * (1 + 1e-9), k_lo, k_hi));
        EXPECT_FALSE(disk_overlaps_box(c, n, d * (1 - 1e-9), k_lo, k_hi));
    }
    {  // plane x + y + z = 1.5 cuts a regular hexagon with vertices at permutations of (1, .5, 0);
       // the centre of the hexagon is (.5,.5,.5); a centre in the plane, 2 away from it along the
       // direction of the vertex (1, .5, 0): the distance is 2 - |vertex - centre|
        const double s = 1 / std::sqrt(3.0);
        const double dir[3] = {0.5 / std::sqrt(0.5), 0.0, -0.5 / std::sqrt(0.5)};
        const double c[3] = {0.5 + 2 * dir[0], 0.5 + 2 * dir[1], 0.5 + 2 * dir[2]}, n[3] = {s, s, s};
        const double expected = 2 - std::sqrt(0.5);
        EXPECT_NEAR(std::sqrt(plane_box_distance_sq(c, n, k_lo, k_hi)), expected, 1e-12);
        EXPECT_NEAR(prt::test::reference_plane_box_distance(c, n, k_lo, k_hi), expected, 1e-12);
    }
    {  // centre inside: always overlaps, whatever the radius
        const double c[3] = {0.25, 0.75, 0.5}, n[3] = {0, 1, 0};
        EXPECT_TRUE(disk_overlaps_box(c, n, 1e-30, k_lo, k_hi));
    }
}

TEST(DiskBox, MatchesIndependentPolygonReference) {
    std::mt19937_64 rng(12345);
    std::uniform_real_distribution<double> u(-1.0, 2.0), unit(-1.0, 1.0), rad(0.01, 1.5);
    int compared = 0, plane_agree = 0;
    for (int it = 0; it < 200000; ++it) {
        double c[3] = {u(rng), u(rng), u(rng)};
        double n[3] = {unit(rng), unit(rng), unit(rng)};
        if (it % 7 == 0) n[it % 3] = 0;               // planes parallel to an axis
        if (it % 11 == 0) n[0] = n[1] = 0, n[2] = 1;  // axis-aligned disks
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (len < 1e-3) continue;
        for (double& x : n) x /= len;
        const double d2 = plane_box_distance_sq(c, n, k_lo, k_hi);
        const double ref = prt::test::reference_plane_box_distance(c, n, k_lo, k_hi);
        if (std::isfinite(ref) != (d2 >= 0)) {
            // a plane grazing the box: only allowed within rounding
            const int call = prt::test::reference_disk_box_overlap(c, n, 1.0, k_lo, k_hi, 1e-9);
            EXPECT_EQ(call, 0) << "plane/box disagreement at iteration " << it;
            continue;
        }
        ++plane_agree;
        if (d2 < 0) continue;
        EXPECT_NEAR(std::sqrt(d2), ref, 1e-9 * (1 + ref)) << "iteration " << it;
        const double r = rad(rng);
        const int call = prt::test::reference_disk_box_overlap(c, n, r, k_lo, k_hi);
        if (call != 0) {
            EXPECT_EQ(disk_overlaps_box(c, n, r, k_lo, k_hi), call > 0) << "iteration " << it;
        }
        ++compared;
    }
    EXPECT_GT(compared, 50000);
    EXPECT_GT(plane_agree, 190000);
}

TEST(DiskBox, SampledDiskPointsInsideImplyOverlap) {
    // Dense polar sampling of the disk: a sample inside the box proves an overlap. The converse does
    // not hold sample by sample (a box corner grazing the disk plane leaves a sliver between the
    // samples), so overlaps the sampling misses are only counted and must be rare.
    std::mt19937_64 rng(777);
    std::uniform_real_distribution<double> u(-0.8, 1.8), unit(-1.0, 1.0), rad(0.05, 1.0);
    int hits = 0, misses = 0, unsampled = 0;
    for (int it = 0; it < 3000; ++it) {
        const double c[3] = {u(rng), u(rng), u(rng)};
        double n[3] = {unit(rng), unit(rng), unit(rng)};
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (len < 1e-3) continue;
        for (double& x : n) x /= len;
        const double r = rad(rng);
        double a[3] = {1, 0, 0};
        if (std::fabs(n[0]) > 0.6) a[0] = 0, a[1] = 1;
        double e1[3] = {n[1] * a[2] - n[2] * a[1], n[2] * a[0] - n[0] * a[2], n[0] * a[1] - n[1] * a[0]};
        const double l1 = std::sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
        for (double& x : e1) x /= l1;
        const double e2[3] = {n[1] * e1[2] - n[2] * e1[1], n[2] * e1[0] - n[0] * e1[2],
                              n[0] * e1[1] - n[1] * e1[0]};
        bool sampled_inside = false;
        const int rings = 48, sectors = 96;
        for (int i = 0; i <= rings && !sampled_inside; ++i)
            for (int j = 0; j < sectors && !sampled_inside; ++j) {
                const double rr = r * i / rings, t = 2 * M_PI * j / sectors;
                const double p[3] = {c[0] + rr * (std::cos(t) * e1[0] + std::sin(t) * e2[0]),
                                     c[1] + rr * (std::cos(t) * e1[1] + std::sin(t) * e2[1]),
                                     c[2] + rr * (std::cos(t) * e1[2] + std::sin(t) * e2[2])};
                sampled_inside = p[0] >= 0 && p[0] <= 1 && p[1] >= 0 && p[1] <= 1 && p[2] >= 0 && p[2] <= 1;
            }
        const bool exact = disk_overlaps_box(c, n, r, k_lo, k_hi);
        if (sampled_inside) {
            EXPECT_TRUE(exact) << "iteration " << it;
            ++hits;
        } else if (exact) {
            ++unsampled;
        } else {
            ++misses;
        }
    }
    EXPECT_GT(hits, 300);
    EXPECT_GT(misses, 300);
    EXPECT_LT(unsampled, hits / 20) << "overlaps claimed where no disk sample lies in the box";
}

}  // namespace
