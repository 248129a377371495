// The compressed splat codec of brick_layout.h (issue 17): round-trip error bounds derived from the
// quantization (not from the code's output), edge cases, and the payload layout arithmetic.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "prt/formats/brick_layout.h"

namespace {

using namespace prt::pool;

constexpr double k_pi = 3.14159265358979323846;

double angle_deg(Float3 a, Float3 b) {
    const double la = std::sqrt(double(a.x) * a.x + double(a.y) * a.y + double(a.z) * a.z);
    const double lb = std::sqrt(double(b.x) * b.x + double(b.y) * b.y + double(b.z) * b.z);
    const double d = (double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z) / (la * lb);
    return std::acos(std::clamp(d, -1.0, 1.0)) * 180.0 / k_pi;
}

/// Ulp of a float at magnitude x.
double ulp(double x) {
    return std::nextafter(float(std::fabs(x)), INFINITY) - float(std::fabs(x));
}

TEST(BrickCodec, PositionWithinHalfAQuantumAtEveryScale) {
    std::mt19937 rng(7);
    for (const double size : {1e-6, 1e-3, 1.0, 37.5, 1e6}) {
        for (const double origin : {0.0, -0.25, 1e3, -5e5}) {
            const float lo = float(origin), qs = float(size);
            const double quantum = double(qs) / 65535.0;
            // float rounding of the decode (lo + q * step) and of the input, at the cube's magnitude
            const double slack = 2.0 * ulp(std::fabs(double(lo)) + double(qs));
            std::uniform_real_distribution<double> u(0.0, 1.0);
            std::vector<float> xs = {lo, float(double(lo) + double(qs)),
                                     float(double(lo) + double(qs) * 0.5)};
            for (int i = 0; i < 20000; ++i) xs.push_back(float(double(lo) + u(rng) * double(qs)));
            for (const float x : xs) {
                const std::uint16_t q = encode_coordinate(x, lo, qs);
                const float y = decode_coordinate(q, lo, qs);
                ASSERT_LE(std::fabs(double(y) - double(x)), 0.5 * quantum + slack)
                    << "x " << x << " lo " << lo << " size " << qs << " code " << q;
            }
            // the cube's faces are codes 0 and 65535; outside clamps (where float holds the faces:
            // a 1e-6 cube at 1e3 is below float's resolution there)
            EXPECT_EQ(encode_coordinate(lo, lo, qs), 0);
            if (double(float(double(lo) + double(qs))) != double(lo) + double(qs)) continue;
            EXPECT_EQ(encode_coordinate(float(double(lo) + double(qs)), lo, qs), 65535);
            EXPECT_EQ(encode_coordinate(lo - qs, lo, qs), 0);
            EXPECT_EQ(encode_coordinate(lo + 2 * qs, lo, qs), 65535);
        }
    }
}

// Bound for the nearest code: a code cell of the [-1,1]^2 octahedral square has edge 1/511, so the
// nearest code is within delta = sqrt(2)/2/511 there; the unfolding onto the octahedron |v|_1 = 1 is
// Lipschitz sqrt(3) (dz = -(sx dx + sy dy)), and the octahedron is at least 1/sqrt(3) from the
// origin, so the angle is at most 3 delta = 0.2379 degrees. The encoder picks the best of the four
// codes around the point, which include the nearest.
constexpr double k_normal_bound_deg = 3.0 * (std::sqrt(2.0) / 2.0 / 511.0) * 180.0 / k_pi + 1e-4;

TEST(BrickCodec, NormalAngleBoundOverTheSphere) {
    // Fibonacci sphere, 200k directions
    const int n = 200000;
    double worst = 0, sum = 0;
    for (int i = 0; i < n; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / n;
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double phi = i * k_pi * (3.0 - std::sqrt(5.0));
        const Float3 v{float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)};
        const double a = angle_deg(decode_octahedral(encode_octahedral(v)), v);
        worst = std::max(worst, a);
        sum += a;
    }
    EXPECT_LE(worst, k_normal_bound_deg);
    EXPECT_GT(worst, 0.0);  // 20 bits cannot be exact everywhere: the test measures something
    std::printf("octahedral 2 x 10 bits: max %.4f deg, mean %.4f deg over %d directions (bound %.4f)\n",
                worst, sum / n, n, k_normal_bound_deg);
}

TEST(BrickCodec, NormalEdgeCases) {
    // axes and the octahedron's vertices are exact
    const Float3 axes[] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const Float3& a : axes) EXPECT_LT(angle_deg(decode_octahedral(encode_octahedral(a)), a), 1e-3);
    // folds: the equator (z = 0), the lower hemisphere's x = 0 and y = 0 meridians, near -z
    std::vector<Float3> edge;
    for (int i = 0; i < 3600; ++i) {
        const double t = 2 * k_pi * i / 3600.0;
        edge.push_back({float(std::cos(t)), float(std::sin(t)), 0.0f});
        edge.push_back({0.0f, float(std::cos(t)), float(std::sin(t))});
        edge.push_back({float(std::cos(t)), 0.0f, float(std::sin(t))});
        edge.push_back({float(1e-7 * std::cos(t)), float(1e-7 * std::sin(t)), -1.0f});
        edge.push_back({float(1e-3 * std::cos(t)), float(1e-3 * std::sin(t)), -1.0f});
    }
    for (const Float3& v : edge) {
        const std::uint32_t code = encode_octahedral(v);
        EXPECT_LE(code & 1023u, k_oct_max_code);
        EXPECT_LE((code >> 10) & 1023u, k_oct_max_code);
        const Float3 d = decode_octahedral(code);
        EXPECT_NEAR(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z, 1.0, 1e-6);
        EXPECT_LE(angle_deg(d, v), k_normal_bound_deg) << v.x << " " << v.y << " " << v.z;
    }
    // a non-unit normal encodes its direction; a zero normal gives +z
    EXPECT_LE(angle_deg(decode_octahedral(encode_octahedral({3, -4, 12})), {3, -4, 12}), k_normal_bound_deg);
    const Float3 z = decode_octahedral(encode_octahedral({0, 0, 0}));
    EXPECT_EQ(z.z, 1.0f);
}

TEST(BrickCodec, RadiusNeverSmallerAndAtMostOneStepLarger) {
    const double step = std::exp2(1.0 / 128.0);
    std::mt19937 rng(11);
    for (const float qs : {1e-6f, 1.0f, 1e6f}) {
        std::uniform_real_distribution<double> lg(-20.0, 3.0);  // radius / brick from 1e-6 to 8
        std::vector<float> radii;
        for (int i = 0; i < 20000; ++i) radii.push_back(float(qs * std::exp2(lg(rng))));
        float max_r = 0;
        for (float r : radii) max_r = std::max(max_r, r);
        const std::int32_t lo = radius_log2_min_for(max_r, qs);
        for (const float r : radii) {
            const std::uint32_t c = encode_radius(r, qs, lo);
            ASSERT_GE(c, 1u);
            ASSERT_LE(c, k_radius_max_code);
            const double d = decode_radius(c, qs, lo);
            ASSERT_GE(d, double(r)) << "radius rounded down: " << r << " -> " << d;
            ASSERT_GE(d * (1.0 - k_radius_margin), double(r) * (1.0 - 1e-7));  // the device margin is kept
            // one step, plus the margin and float rounding
            ASSERT_LE(d, double(r) * step * (1.0 + 4e-6)) << r;
        }
        EXPECT_LE(encode_radius(max_r, qs, lo), k_radius_max_code);
        // the exponent's range: 32 octaves below the largest radius
        const float tiny = float(max_r * std::exp2(-40.0));
        const std::uint32_t ct = encode_radius(tiny, qs, lo);
        EXPECT_EQ(ct, 1u);  // below the range: raised to the smallest code, never rounded down
        EXPECT_GE(decode_radius(ct, qs, lo), tiny);
        // above the range: reported, not stored
        EXPECT_GT(encode_radius(max_r * 1e3f, qs, lo), k_radius_max_code);
    }
    // degenerate radii: 0, negative, NaN, inf -> code 0 -> radius 0
    for (const float r : {0.0f, -1.0f, NAN, INFINITY}) {
        EXPECT_EQ(encode_radius(r, 1.0f, -20), 0u);
    }
    EXPECT_EQ(decode_radius(0, 1.0f, -20), 0.0f);
}

TEST(BrickCodec, ColourBounds) {
    // round to nearest of 31 (63) levels: within 255/62 = 4.11 (255/126 = 2.02) of the level's exact
    // value, then rounded to an integer on decode: at most 4 (2)
    int worst_rb = 0, worst_g = 0;
    for (int v = 0; v < 256; ++v) {
        const auto u = static_cast<std::uint8_t>(v);
        const Rgba8 d = decode_rgb565(encode_rgb565({u, u, u, 17}));
        worst_rb = std::max({worst_rb, std::abs(int(d.r) - v), std::abs(int(d.b) - v)});
        worst_g = std::max(worst_g, std::abs(int(d.g) - v));
        EXPECT_EQ(d.a, 255);
    }
    EXPECT_LE(worst_rb, 4);
    EXPECT_LE(worst_g, 2);
    EXPECT_GT(worst_rb, 0);
    const Rgba8 black = decode_rgb565(encode_rgb565({0, 0, 0, 255}));
    const Rgba8 white = decode_rgb565(encode_rgb565({255, 255, 255, 255}));
    EXPECT_EQ(black.r + black.g + black.b, 0);
    EXPECT_EQ(white.r + white.g + white.b, 3 * 255);
    // channels do not leak into each other
    const Rgba8 red = decode_rgb565(encode_rgb565({255, 0, 0, 255}));
    EXPECT_EQ(red.g + red.b, 0);
    const Rgba8 green = decode_rgb565(encode_rgb565({0, 255, 0, 255}));
    EXPECT_EQ(green.r + green.b, 0);
}

TEST(BrickCodec, SplatRoundTripOnTheBrickBoundary) {
    for (const float qs : {1e-6f, 1.0f, 1e6f}) {
        BrickHeader h{};
        h.quant_min[0] = -qs;
        h.quant_min[1] = 2 * qs;
        h.quant_min[2] = 0;
        h.quant_size = qs;
        h.radius_log2_min = radius_log2_min_for(qs * 0.5f, qs);
        const double quantum = double(qs) / 65535.0;
        // the eight corners of the cube and a centre
        for (int c = 0; c < 9; ++c) {
            const Float3 p =
                c < 8 ? Float3{h.quant_min[0] + ((c & 1) ? qs : 0.0f), h.quant_min[1] + ((c & 2) ? qs : 0.0f),
                               h.quant_min[2] + ((c & 4) ? qs : 0.0f)}
                      : Float3{h.quant_min[0] + qs / 2, h.quant_min[1] + qs / 2, h.quant_min[2] + qs / 2};
            const Float3 n{0.0f, 0.6f, -0.8f};
            CompressedSplat s{};
            ASSERT_TRUE(encode_splat(p, qs * 1e-3f, n, {10, 200, 30, 255}, h, &s));
            const DecodedSplat d = decode_splat(s, h);
            const double slack = 2.0 * ulp(3.0 * qs);
            EXPECT_LE(std::fabs(double(d.position.x) - p.x), 0.5 * quantum + slack);
            EXPECT_LE(std::fabs(double(d.position.y) - p.y), 0.5 * quantum + slack);
            EXPECT_LE(std::fabs(double(d.position.z) - p.z), 0.5 * quantum + slack);
            EXPECT_GE(d.radius, qs * 1e-3f);
            EXPECT_LE(angle_deg(d.normal, n), k_normal_bound_deg);
            EXPECT_LE(std::abs(int(d.color.g) - 200), 2);
        }
        // a radius the exponent cannot hold is refused
        CompressedSplat s{};
        EXPECT_FALSE(encode_splat({0, 0, 0}, qs * 1e12f, {0, 0, 1}, {0, 0, 0, 0}, h, &s));
    }
}

TEST(BrickCodec, PayloadLayout) {
    // header 48 B, then 4 B per node, 4 B per leaf_info entry (leaves + 1), a 2-byte reference per
    // leaf splat (4-byte when a brick encodes more than 65536 splats), padded to 4, 12 B per
    // encoded splat
    EXPECT_EQ(brick_payload_size(1, 0, 0, 0), 48u + 4u + 4u);
    EXPECT_EQ(brick_payload_size(9, 5, 100, 40), 48u + 36u + 24u + 200u + 480u);
    EXPECT_EQ(brick_payload_size(9, 5, 101, 40), 48u + 36u + 24u + 204u + 480u);  // 202 padded to 204
    EXPECT_EQ(brick_splats_offset(9, 5, 101, 40) % 4, 0u);
    EXPECT_EQ(brick_ref_bytes(65536), 2u);
    EXPECT_EQ(brick_ref_bytes(65537), 4u);
    EXPECT_EQ(brick_payload_size(1, 1, 70000, 65537), 48u + 4u + 8u + 280000u + 12u * 65537u);
    EXPECT_EQ(sizeof(CompressedSplat), 12u);
}

}  // namespace
