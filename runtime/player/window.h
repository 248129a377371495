// PointRT player: the interactive GLFW window (built only with PRT_HAVE_PRT_WITH_GLFW).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "player_options.h"
#include "prt/runtime/backend.h"
#include "prt/runtime/brick_stream.h"
#include "prt/runtime/render_scene.h"
#include "window_controls.h"

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
    /// Keys pressed by script, one before each of the first frames (GLFW key codes; --keys).
    std::vector<int> keys;
    /// Screenshots (C) go to SAVE_PREFIX-NNNN.png (.ppm without OpenImageIO), recorded camera
    /// paths (L) to SAVE_PREFIX-path-NNNN.txt, numbered from 1 past the files that exist.
    std::string save_prefix = "prt-play";
    /// Loads the scene again with every model as this surface (LoadOptions::surface), for K; throws
    /// prt::Error when a pool lacks it. Empty: K says the scene cannot switch.
    SurfaceReload reload;
};

/// Opens a window and renders until it is closed. The controls are window_controls.h's (key_help()
/// lists them): mouse orbit, pan, zoom and click to pick; WASD/QE fly; R resets the view; 1-4
/// toggle shadows, reflections, refractions, deep blending; P progressive path tracing; K next
/// surface; B next backend; C screenshot; L records a camera path; H prints the list. The title
/// shows the backend, surface, frame time, rays/s, toggles and the accumulated samples. With the CUDA
/// backend, frames reach the screen through CUDA-OpenGL interop (a pixel buffer the kernels write,
/// then copied into the texture on the GPU) where the GL context runs on the CUDA device; otherwise
/// (CPU and hybrid backends, or registration refused) as a texture upload of the rendered image.
/// Streamed bricks (`stream`, made for `backend`; remade when B switches backends) refine frame after
/// frame: each frame uploads the bricks the previous one asked for; the title shows the resident
/// bricks and the rays that used a coarse level.
void run_window(rt::RenderScene& scene, std::unique_ptr<rt::Backend>& backend,
                std::unique_ptr<rt::BrickStream>& stream, const WindowOptions& options);

}  // namespace prt::player
