// prt-play's GLFW window end to end (label cpu): under a virtual X server (xvfb-run, or the X display
// in $DISPLAY), the player
// opens its window with the CPU backend, shows a few frames and writes the displayed framebuffer
// (--screenshot, read back with glReadPixels); the capture must be a real render (not blank: the
// model in the middle, the background in the corners) and match the headless render of the same
// view. Skips with a message where the build has no window (GLFW) or xvfb-run is not installed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "prt/runtime/image.h"
#include "window_fixture.h"

namespace prt::test {
namespace {

namespace fs = std::filesystem;

TEST_F(WindowTest, ScreenshotArgumentsAreCheckedBeforeAnyWindowOpens) {
    const std::string pool = (m_dir / "ball.pool").string();
    const ToolRun headless = run_tool(
        "prt-play", pool + " --backend cpu --headless --screenshot " + (m_dir / "a.ppm").string(), m_dir);
    EXPECT_EQ(headless.code, 1);
    EXPECT_EQ(lines(headless.err), 1) << headless.err;
    EXPECT_NE(headless.err.find("--screenshot"), std::string::npos) << headless.err;
    const ToolRun linear =
        run_tool("prt-play", pool + " --backend cpu --screenshot " + (m_dir / "a.pfm").string(), m_dir);
    EXPECT_EQ(linear.code, 1);
    EXPECT_EQ(lines(linear.err), 1) << linear.err;
    EXPECT_FALSE(fs::exists(m_dir / "a.ppm"));
    EXPECT_FALSE(fs::exists(m_dir / "a.pfm"));
}

TEST_F(WindowTest, ScreenshotUnderXvfbMatchesTheHeadlessRender) {
#ifndef PRT_TEST_HAVE_WINDOW
    GTEST_SKIP() << "this build has no player window (configured without GLFW)";
#endif
    const std::optional<std::string> x = display_prefix();
    if (!x)
        GTEST_SKIP() << "no X display and xvfb-run is not installed (Debian: apt-get install xvfb xauth): "
                        "window test skipped";
    const std::string pool = (m_dir / "ball.pool").string();
    // The default view, and one turned to another up by the camera options (the window's orbit
    // starts from the same camera).
    for (const std::string& camera : {std::string(), std::string(" --up 1,1,0.3 --fov 35")}) {
        SCOPED_TRACE(camera);
        const std::string view = " --backend cpu --width 96 --height 72 --max-bounces 1" + camera;
        const fs::path shot = m_dir / "shot.ppm", ref = m_dir / "ref.ppm";
        const ToolRun win =
            run_tool("prt-play", pool + view + " --frames 3 --screenshot " + shot.string(), m_dir, *x);
        ASSERT_EQ(win.code, 0) << win.err;
        EXPECT_NE(win.err.find("after 3 frames"), std::string::npos) << win.err;
        const ToolRun head = run_tool("prt-play", pool + view + " --out " + ref.string(), m_dir);
        ASSERT_EQ(head.code, 0) << head.err;

        expect_window_shows(shot, ref, 96, 72);
    }
}

TEST_F(WindowTest, ScriptedKeysTakeAScreenshotAndRecordAReplayablePath) {
#ifndef PRT_TEST_HAVE_WINDOW
    GTEST_SKIP() << "this build has no player window (configured without GLFW)";
#endif
    const std::optional<std::string> x = display_prefix();
    if (!x)
        GTEST_SKIP() << "no X display and xvfb-run is not installed (Debian: apt-get install xvfb xauth): "
                        "window test skipped";
    const std::string pool = (m_dir / "ball.pool").string();
    const std::string view = " --backend cpu --width 96 --height 72 --max-bounces 1 --up 0.2,1,0 --fov 40";
    // Frame 0: L starts recording; frame 1: C takes a screenshot; frame 2: L stops (2 frames recorded);
    // frame 3: K looks for another surface (this pool has splats only).
    const std::string prefix = (m_dir / "w").string();
    const ToolRun win =
        run_tool("prt-play", pool + view + " --frames 4 --keys L,C,L,K --save-prefix " + prefix, m_dir, *x);
    ASSERT_EQ(win.code, 0) << win.err;
    const std::string ext = rt::have_oiio() ? ".png" : ".ppm";
    const fs::path shot = prefix + "-0001" + ext, path = prefix + "-path-0001.txt";
    ASSERT_TRUE(fs::exists(shot)) << win.err;
    ASSERT_TRUE(fs::exists(path)) << win.err;
    EXPECT_NE(win.err.find("recorded 2 frames"), std::string::npos) << win.err;
    EXPECT_NE(win.err.find("no other surface in the pools"), std::string::npos) << win.err;
    // The recorded path replayed headless renders what the window showed.
    const fs::path ref = m_dir / ("replay" + ext);
    const ToolRun head = run_tool(
        "prt-play", pool + view + " --camera-path " + path.string() + " --frames 1 --out " + ref.string(),
        m_dir);
    ASSERT_EQ(head.code, 0) << head.err;
    const rt::FloatImage a = rt::read_float_image(shot), b = rt::read_float_image(ref);
    ASSERT_EQ(a.width, 96u);
    ASSERT_EQ(a.height, 72u);
    ASSERT_EQ(b.width, a.width);
    ASSERT_EQ(b.height, a.height);
    ASSERT_EQ(a.rgb.size(), b.rgb.size());
    double sum = 0, lo = 1, hi = 0;
    for (std::size_t i = 0; i < a.rgb.size(); ++i) {
        sum += std::fabs(a.rgb[i] - b.rgb[i]);
        lo = std::min<double>(lo, a.rgb[i]);
        hi = std::max<double>(hi, a.rgb[i]);
    }
    EXPECT_GT(hi - lo, 0.3) << "the screenshot is (nearly) blank";
    EXPECT_LE(sum / a.rgb.size(), 1.0 / 255) << "mean difference";
    // A second screenshot takes the next number.
    const ToolRun again =
        run_tool("prt-play", pool + view + " --frames 1 --keys C --save-prefix " + prefix, m_dir, *x);
    ASSERT_EQ(again.code, 0) << again.err;
    EXPECT_TRUE(fs::exists(prefix + "-0002" + ext)) << again.err;
}

}  // namespace
}  // namespace prt::test
