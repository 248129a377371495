// PointRT player: the interactive GLFW window (built only with PRT_HAVE_PRT_WITH_GLFW).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>

#include "player_options.h"
#include "prt/runtime/backend.h"
#include "prt/runtime/brick_stream.h"
#include "prt/runtime/render_scene.h"

namespace prt::player {

struct WindowOptions {
    BackendChoice backend;
    bool quiet = false;
    /// Frames to show before closing the window by itself (0: until the user closes it).
    std::uint32_t frames = 0;
    /// When set: after `frames` frames (at least 1), the displayed framebuffer is read back
    /// (glReadPixels) and written here as an 8-bit image, then the window closes.
    std::filesystem::path screenshot;
    /// CUDA backend: render straight into an OpenGL pixel buffer through CUDA-OpenGL interop
    /// (builds with CUDA and OpenGL); false keeps the texture upload.
    bool interop = true;
};

/// Opens a window and renders until it is closed. Mouse: left drag orbits about the look-at
/// point, right (or middle) drag pans, the wheel zooms. Keys: S shadows, R reflections,
/// T refractions, D deep blending, K surface kind, B next backend (cpu / cuda / hybrid, those this
/// machine runs), Esc quits. The title shows the backend, frame time and toggles. With the CUDA
/// backend, frames reach the screen through CUDA-OpenGL interop (a pixel buffer the kernels write,
/// then copied into the texture on the GPU) where the GL context runs on the CUDA device; otherwise
/// (CPU and hybrid backends, or registration refused) as a texture upload of the rendered image.
/// Streamed bricks (`stream`, made for `backend`; remade when B switches backends) refine frame after
/// frame: each frame uploads the bricks the previous one asked for; the title shows the resident
/// bricks and the rays that used a coarse level.
void run_window(rt::RenderScene& scene, std::unique_ptr<rt::Backend>& backend,
                std::unique_ptr<rt::BrickStream>& stream, const WindowOptions& options);

}  // namespace prt::player
