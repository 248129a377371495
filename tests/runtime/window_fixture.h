// The player window's test scene and checks, shared by window_test.cpp (CPU backend, label cpu) and
// window_gpu_test.cpp (CUDA backend through CUDA-OpenGL interop, label gpu).
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <set>

#include "prt/runtime/image.h"
#include "test_scene.h"
#include "tool_fixture.h"
#include "tool_run.h"

namespace prt::test {

class WindowTest : public FolderTest {
protected:
    WindowTest() : FolderTest("prt_window_test_") {}
    void SetUp() override {
        FolderTest::SetUp();
        // A red ball in front of a grey wall: shading, a shadow and a silhouette to compare.
        std::vector<TestPoint> pts = sphere_points({0, 0, 0}, 1.0, 6000, false, {250, 60, 40, 255});
        const auto wall = rect_points({-3, -3, -1.5}, {6, 0, 0}, {0, 6, 0}, {0, 0, 1}, 90);
        pts.insert(pts.end(), wall.begin(), wall.end());
        const auto pool = make_pool(make_model(pts, {0, 0, 0}));
        write_pool(*pool, m_dir / "ball.pool");
    }
};

inline int channel(std::uint32_t p, int c) {
    return static_cast<int>((p >> (8 * c)) & 0xffu);
}

/// The window's screenshot `shot` (PPM) is a real render of the ball scene (the red ball in the
/// middle, something else in a corner) and equals the headless render `ref` of the same frame
/// within 8-bit rounding: the texture is drawn texel for pixel.
inline void expect_window_shows(const std::filesystem::path& shot, const std::filesystem::path& ref,
                                std::uint32_t width, std::uint32_t height) {
    const rt::Image a = rt::read_ppm(shot), b = rt::read_ppm(ref);
    ASSERT_EQ(a.width, width);
    ASSERT_EQ(a.height, height);
    ASSERT_EQ(b.width, a.width);
    ASSERT_EQ(b.height, a.height);
    // A real render: many distinct colors, the red ball in the middle, something else in a corner.
    std::set<std::uint32_t> distinct(a.rgba8.begin(), a.rgba8.end());
    EXPECT_GT(distinct.size(), 50u) << "the screenshot is (nearly) blank";
    const std::uint32_t centre = a.rgba8[(height / 2) * width + width / 2], corner = a.rgba8[0];
    EXPECT_GT(channel(centre, 0), 2 * channel(centre, 1)) << "the centre is not the red ball";
    EXPECT_NE(centre, corner);
    // The window shows what the headless render computes: the texture is drawn texel for pixel.
    double sum = 0;
    std::size_t off = 0;
    for (std::size_t i = 0; i < a.rgba8.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
            const int d = std::abs(channel(a.rgba8[i], c) - channel(b.rgba8[i], c));
            sum += d;
            off += d > 2;
        }
    }
    EXPECT_LE(sum / (3.0 * a.rgba8.size()), 0.5) << "mean difference in 8-bit levels";
    EXPECT_LE(off, a.rgba8.size() * 3 / 100) << "channels more than 2 levels apart";
}

}  // namespace prt::test
