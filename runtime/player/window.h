// PointRT player: the interactive GLFW window (built only with PRT_HAVE_PRT_WITH_GLFW).
#pragma once

#include <memory>

#include "player_options.h"
#include "prt/runtime/backend.h"
#include "prt/runtime/render_scene.h"

namespace prt::player {

struct WindowOptions {
    BackendChoice backend;
    bool quiet = false;
};

/// Opens a window and renders until it is closed. Mouse: left drag orbits about the look-at
/// point, right (or middle) drag pans, the wheel zooms. Keys: S shadows, R reflections,
/// T refractions, D deep blending, K surface kind, B next backend (cpu / cuda / hybrid, those this
/// machine runs), Esc quits. The title shows the backend, frame time and toggles. Frames reach the
/// screen as a texture upload of the rendered image (both backends).
void run_window(rt::RenderScene& scene, std::unique_ptr<rt::Backend>& backend, const WindowOptions& options);

}  // namespace prt::player
