// Tri-planar projection math (preprocess/texture/triplanar.h, thesis 5.5 eq. 5.5) and the baking
// loop (texture_bake.h). References are written out here from the equation and the documented
// plane conventions, never taken from the code's own output.
#include "triplanar.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "prt/error.h"
#include "texture_bake.h"

namespace {

using namespace prt::pre::texture;

/// A W x H image whose texel (x, y) (row y from the top) has the color f(x, y).
template <class F>
std::vector<float> make_image(std::uint32_t w, std::uint32_t h, F f) {
    std::vector<float> px(static_cast<std::size_t>(w) * h * 3);
    for (std::uint32_t y = 0; y < h; ++y)
        for (std::uint32_t x = 0; x < w; ++x) {
            const D3 c = f(x, y);
            for (int i = 0; i < 3; ++i)
                px[(static_cast<std::size_t>(y) * w + x) * 3 + i] = static_cast<float>(c[i]);
        }
    return px;
}

D3 random_unit(std::mt19937& rng) {
    std::normal_distribution<double> g;
    for (;;) {
        const D3 v{g(rng), g(rng), g(rng)};
        const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (l > 1e-6) return {v[0] / l, v[1] / l, v[2] / l};
    }
}

TEST(TriplanarWeights, SumToOneAndAreNonNegative) {
    std::mt19937 rng(7);
    for (double k : {0.0, 0.5, 1.0, 2.0, 8.0, 64.0, 500.0}) {
        for (int i = 0; i < 2000; ++i) {
            const D3 n = random_unit(rng);
            const D3 w = triplanar_weights(n, k);
            EXPECT_NEAR(w[0] + w[1] + w[2], 1.0, 1e-12) << "K = " << k;
            for (double x : w) {
                EXPECT_GE(x, 0.0);
                EXPECT_TRUE(std::isfinite(x));
            }
        }
    }
}

TEST(TriplanarWeights, KOneIsEquation5_5WithAbsoluteDots) {
    // eq. 5.5: weights n . n_a over their sum; |.| so that -x faces count like +x faces.
    std::mt19937 rng(11);
    for (int i = 0; i < 1000; ++i) {
        const D3 n = random_unit(rng);
        const double s = std::fabs(n[0]) + std::fabs(n[1]) + std::fabs(n[2]);
        const D3 w = triplanar_weights(n, 1.0);
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(w[a], std::fabs(n[a]) / s, 1e-12);
    }
    // K = 2: squares over their sum, which for a unit normal is 1.
    const D3 n{0.6, -0.8, 0.0};
    const D3 w2 = triplanar_weights(n, 2.0);
    EXPECT_NEAR(w2[0], 0.36, 1e-12);
    EXPECT_NEAR(w2[1], 0.64, 1e-12);
    EXPECT_EQ(w2[2], 0.0);
}

TEST(TriplanarWeights, AxisNormalsSelectOnePlaneAndDegenerateNormalsAreDefined) {
    for (int a = 0; a < 3; ++a)
        for (double sign : {1.0, -1.0}) {
            D3 n{0, 0, 0};
            n[a] = sign;
            const D3 w = triplanar_weights(n, 1.0);
            for (int b = 0; b < 3; ++b) EXPECT_EQ(w[b], a == b ? 1.0 : 0.0);
        }
    for (const D3& n : {D3{0, 0, 0}, D3{NAN, 0, 1}, D3{INFINITY, 0, 0}}) {
        const D3 w = triplanar_weights(n, 4.0);
        for (double x : w) EXPECT_DOUBLE_EQ(x, 1.0 / 3.0);
    }
    // A large K must not underflow every weight: the dominant plane wins.
    const D3 w = triplanar_weights({0.5, 0.7, std::sqrt(1 - 0.74)}, 1000.0);
    EXPECT_NEAR(w[1], 1.0, 1e-12);
}

TEST(Triplanar, ConstantTextureGivesConstantColor) {
    const std::vector<float> img = make_image(5, 3, [](std::uint32_t, std::uint32_t) {
        return D3{0.25, 0.5, 2.0};
    });
    const TextureView t{img.data(), 5, 3};
    const TextureView tex[3] = {t, t, t};
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> pos(-1e3, 1e3);
    for (double scale : {1e-3, 0.37, 250.0}) {
        for (double k : {1.0, 4.0}) {
            const TriplanarParams params{scale, k, {1.5, -2.0, 7.0}};
            for (int i = 0; i < 500; ++i) {
                const D3 c = triplanar_color(tex, {pos(rng), pos(rng), pos(rng)}, random_unit(rng), params);
                EXPECT_NEAR(c[0], 0.25, 1e-12);
                EXPECT_NEAR(c[1], 0.5, 1e-12);
                EXPECT_NEAR(c[2], 2.0, 1e-12);
            }
        }
    }
}

TEST(Triplanar, AxisAlignedPlanesTakeExactlyTheirProjection) {
    // Three different images; a point on an axis-aligned plane, with that plane's normal (either
    // sign), must get its own image's texel at its projection and nothing of the other two.
    const std::uint32_t w = 8, h = 4;
    const std::vector<float> ix = make_image(w, h, [](std::uint32_t x, std::uint32_t y) {
        return D3{double(x), double(y), 1};
    });
    const std::vector<float> iy = make_image(w, h, [](std::uint32_t x, std::uint32_t y) {
        return D3{double(x), double(y), 2};
    });
    const std::vector<float> iz = make_image(w, h, [](std::uint32_t x, std::uint32_t y) {
        return D3{double(x), double(y), 3};
    });
    const TextureView tex[3] = {{ix.data(), w, h}, {iy.data(), w, h}, {iz.data(), w, h}};
    const double scale = 2.0;
    const D3 origin{10, 20, 30};
    const TriplanarParams params{scale, 1.0, origin};
    for (int axis = 0; axis < 3; ++axis) {
        for (double sign : {1.0, -1.0}) {
            for (std::uint32_t col = 0; col < w; ++col) {
                for (std::uint32_t row = 0; row < h; ++row) {
                    for (int repeat : {-2, 0, 3}) {
                        // Texel centre in plane coordinates: u = (col + 0.5) / w repeats, v counted
                        // up from the image's bottom edge.
                        const double u = scale * ((col + 0.5) / w + repeat);
                        const double v = scale * (1.0 - (row + 0.5) / h - repeat);
                        // The documented plane frames: x plane (u, v) = (-z, y), y plane (x, -z),
                        // z plane (x, y), relative to the origin; the off-plane coordinate is free.
                        D3 p{};
                        if (axis == 0) p = {origin[0] + 0.7, origin[1] + v, origin[2] - u};
                        if (axis == 1) p = {origin[0] + u, origin[1] - 3.1, origin[2] - v};
                        if (axis == 2) p = {origin[0] + u, origin[1] + v, origin[2] + 12.0};
                        D3 n{0, 0, 0};
                        n[axis] = sign;
                        const D3 c = triplanar_color(tex, p, n, params);
                        EXPECT_NEAR(c[0], col, 1e-9) << "axis " << axis << " col " << col << " row " << row;
                        EXPECT_NEAR(c[1], row, 1e-9) << "axis " << axis << " col " << col << " row " << row;
                        EXPECT_NEAR(c[2], axis + 1.0, 1e-12);
                    }
                }
            }
        }
    }
}

TEST(Triplanar, ObliqueNormalAveragesTheProjections) {
    // n = (1, 1, 0) / sqrt 2: half the x plane's sample plus half the y plane's (eq. 5.5).
    const std::vector<float> ix = make_image(2, 2, [](std::uint32_t, std::uint32_t) { return D3{1, 0, 0}; });
    const std::vector<float> iy = make_image(2, 2, [](std::uint32_t, std::uint32_t) { return D3{0, 1, 0}; });
    const std::vector<float> iz = make_image(2, 2, [](std::uint32_t, std::uint32_t) { return D3{0, 0, 1}; });
    const TextureView tex[3] = {{ix.data(), 2, 2}, {iy.data(), 2, 2}, {iz.data(), 2, 2}};
    const double r = 1.0 / std::sqrt(2.0);
    const D3 c = triplanar_color(tex, {0.3, 0.1, 0.2}, {r, -r, 0}, TriplanarParams{});
    EXPECT_NEAR(c[0], 0.5, 1e-12);
    EXPECT_NEAR(c[1], 0.5, 1e-12);
    EXPECT_NEAR(c[2], 0.0, 1e-12);
    // A unit normal with equal components weighs all three equally for any K.
    const double q = 1.0 / std::sqrt(3.0);
    const D3 e = triplanar_color(tex, {0.3, 0.1, 0.2}, {q, q, -q}, TriplanarParams{1.0, 5.0, {0, 0, 0}});
    for (double x : e) EXPECT_NEAR(x, 1.0 / 3.0, 1e-12);
}

TEST(TriplanarSample, BilinearBetweenTexelsAndWrapsAtEdges) {
    // One row of 4 texels with values 0, 1, 2, 3 (red channel).
    const std::vector<float> img = make_image(4, 1, [](std::uint32_t x, std::uint32_t) {
        return D3{double(x), 0, 0};
    });
    const TextureView t{img.data(), 4, 1};
    // Halfway between the centres of texels 1 and 2 (s = 1.5 / 4 ... 2.5 / 4).
    EXPECT_NEAR(sample_wrap_bilinear(t, 2.0 / 4.0, 0.5)[0], 1.5, 1e-12);
    EXPECT_NEAR(sample_wrap_bilinear(t, 1.75 / 4.0, 0.5)[0], 1.25, 1e-12);
    // Across the wrap: halfway between texel 3 and texel 0 is s = 0 (and 1, and -7).
    for (double s : {0.0, 1.0, -7.0, 1e6}) EXPECT_NEAR(sample_wrap_bilinear(t, s, 0.5)[0], 1.5, 1e-9) << s;
    // Periodic in both coordinates.
    for (double s : {0.1, 0.37, 0.93})
        for (int k : {-3, 1, 40}) {
            EXPECT_NEAR(sample_wrap_bilinear(t, s + k, 0.2 - k)[0], sample_wrap_bilinear(t, s, 0.2)[0], 1e-9);
        }
    // Vertical: rows from the top, t upwards. Row 0 = 10 (top), row 1 = 20 (bottom).
    const std::vector<float> col = make_image(1, 2, [](std::uint32_t, std::uint32_t y) {
        return D3{y == 0 ? 10.0 : 20.0, 0, 0};
    });
    const TextureView tc{col.data(), 1, 2};
    EXPECT_NEAR(sample_wrap_bilinear(tc, 0.5, 0.75)[0], 10.0, 1e-12);  // upper half's centre
    EXPECT_NEAR(sample_wrap_bilinear(tc, 0.5, 0.25)[0], 20.0, 1e-12);  // lower half's centre
    EXPECT_NEAR(sample_wrap_bilinear(tc, 0.5, 0.5)[0], 15.0, 1e-12);
}

TEST(TriplanarSrgb, EncodingRoundTripsEveryByte) {
    for (int v = 0; v < 256; ++v)
        EXPECT_EQ(linear_to_srgb8(srgb8_to_linear(static_cast<std::uint8_t>(v))), v);
    EXPECT_EQ(linear_to_srgb8(-1.0), 0);
    EXPECT_EQ(linear_to_srgb8(NAN), 0);
    EXPECT_EQ(linear_to_srgb8(7.0), 255);
    EXPECT_EQ(linear_to_srgb8(0.5), 188);  // 1.055 * 0.5^(1/2.4) - 0.055 = 0.7354 -> 187.5 -> 188
    // Against the encoding formula itself, over [0, 1].
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int i = 0; i < 200000; ++i) {
        const double c = i < 1000 ? i / 1000.0 : u(rng);
        const double e = c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
        ASSERT_EQ(linear_to_srgb8(c), std::lround(255.0 * e)) << "c = " << c;
    }
}

TEST(TriplanarBake, ReplaceMultiplyAndAlpha) {
    const std::vector<float> img = make_image(3, 3, [](std::uint32_t, std::uint32_t) {
        return D3{0.5, 0.5, 0.5};
    });
    const TextureView t{img.data(), 3, 3};
    const TextureView tex[3] = {t, t, t};
    const std::vector<prt::pool::Float3> pos{{0, 0, 0}, {1, 2, 3}, {-4, 5, 0.5f}};
    const std::vector<prt::pool::Float3> nrm{{0, 0, 1}, {0.6f, 0.8f, 0}, {0, 0, 0}};
    const std::vector<prt::pool::Rgba8> old{{255, 255, 255, 7}, {255, 0, 128, 255}, {10, 20, 30, 40}};
    const TriplanarParams params{0.3, 1.0, {0, 0, 0}};
    const auto rep = bake_triplanar(pos, nrm, old, {1e6, 0, -1e6}, tex, params, Blend::replace, 2);
    const auto mul = bake_triplanar(pos, nrm, old, {1e6, 0, -1e6}, tex, params, Blend::multiply, 1);
    const auto none = bake_triplanar(pos, nrm, {}, {0, 0, 0}, tex, params, Blend::multiply, 1);
    ASSERT_EQ(rep.size(), 3u);
    for (std::size_t i = 0; i < 3; ++i) {
        EXPECT_EQ(rep[i].r, 188);  // linear 0.5 encoded
        EXPECT_EQ(rep[i].g, 188);
        EXPECT_EQ(rep[i].a, old[i].a) << "alpha is carried over";
        EXPECT_EQ(none[i].r, 188) << "no old colors: multiply by white";
        EXPECT_EQ(none[i].a, 255);
    }
    EXPECT_EQ(mul[0].r, 188);  // white x 0.5
    EXPECT_EQ(mul[1].g, 0);    // black x 0.5
    // 128 (sRGB) x 0.5 in linear: 0.21586 x 0.5 = 0.10793 -> sRGB 0.36225 -> 92.37 -> 92.
    EXPECT_EQ(mul[1].b, linear_to_srgb8(0.5 * std::pow((128 / 255.0 + 0.055) / 1.055, 2.4)));
    EXPECT_EQ(mul[1].b, 92);

    EXPECT_THROW(bake_triplanar(pos, std::span(nrm).first(2), {}, {0, 0, 0}, tex, params, Blend::replace),
                 prt::Error);
    EXPECT_THROW(bake_triplanar(pos, nrm, std::span(old).first(1), {0, 0, 0}, tex, params, Blend::replace),
                 prt::Error);
    EXPECT_THROW(
        bake_triplanar(pos, nrm, {}, {0, 0, 0}, tex, TriplanarParams{0.0, 1.0, {0, 0, 0}}, Blend::replace),
        prt::Error);
}

}  // namespace
