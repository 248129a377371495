// prt-play's GLFW window on the CUDA backend (label gpu, issue 18): the kernels render into an
// OpenGL pixel buffer through CUDA-OpenGL interop and the window shows it; the screenshot read back
// from the window's framebuffer must equal the headless CUDA render of the same frame. Needs an X
// display whose GLX runs on the CUDA device: on the GPU machine, an Xvfb with the NVIDIA GLX vendor
// library (__GLX_VENDOR_LIBRARY_NAME=nvidia; scripts/gpu-window.sh starts one). Skips with a
// message without a CUDA device, a window build or an X display; fails where the window falls back
// to a texture upload (the GL context is not on the CUDA device).
#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "prt/runtime/backend.h"
#include "window_fixture.h"

namespace prt::test {
namespace {

namespace fs = std::filesystem;

TEST_F(WindowTest, CudaFramesReachTheWindowThroughInteropAndMatchTheHeadlessRender) {
#ifndef PRT_TEST_HAVE_WINDOW
    GTEST_SKIP() << "this build has no player window (configured without GLFW)";
#endif
    const rt::BackendAvailability a = rt::backend_availability();
    if (!a.cuda_device) GTEST_SKIP() << "no CUDA device: " << a.cuda_why;
    const std::optional<std::string> x = display_prefix();
    if (!x) GTEST_SKIP() << "no X display and xvfb-run is not installed: window test skipped";
    const std::string pool = (m_dir / "ball.pool").string();
    // Two frame sizes (the pixel buffer and the texture take the frame's size).
    for (const auto& [w, h] : {std::pair{96u, 72u}, std::pair{160u, 120u}}) {
        SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
        const std::string view =
            " --backend cuda --max-bounces 1 --width " + std::to_string(w) + " --height " + std::to_string(h);
        const fs::path shot = m_dir / "shot.ppm", ref = m_dir / "ref.ppm";
        const ToolRun win =
            run_tool("prt-play", pool + view + " --frames 4 --screenshot " + shot.string(), m_dir, *x);
        ASSERT_EQ(win.code, 0) << win.err;
        EXPECT_NE(win.err.find("frames reach the window through CUDA-OpenGL interop"), std::string::npos)
            << win.err;
        EXPECT_NE(win.err.find("after 4 frames, interop"), std::string::npos) << win.err;
        EXPECT_NE(win.err.find("3 frames after the first"), std::string::npos) << win.err;
        const ToolRun head = run_tool("prt-play", pool + view + " --out " + ref.string(), m_dir);
        ASSERT_EQ(head.code, 0) << head.err;
        expect_window_shows(shot, ref, w, h);
    }
}

}  // namespace
}  // namespace prt::test
