// PointRT player: options shared by prt-play and prt-bench (render-setting overrides).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

#include "prt/core/scene_view.h"
#include "prt/runtime/backend.h"

namespace prt::player {

/// Render settings a command line may override (unset = keep the scene file's).
struct RenderOverrides {
    std::string tone_map = "clamp";
    float exposure = 0;    ///< 0: keep
    int max_bounces = -1;  ///< -1: keep
    bool no_shadows = false, no_reflections = false, no_refractions = false;
    bool deep_blending = false;
    float blend_window = 1.0f;
    std::uint32_t max_steps = 1u << 16;
    std::uint32_t leaf_culling = 2;  ///< core::LeafCulling
};

/// Backend choice.
struct BackendChoice {
    std::string name = "auto";
    std::string kernel = "mega";     ///< cuda: "mega" or "wavefront"
    std::string mapping = "zorder";  ///< cuda: "zorder" or "linear"
    unsigned threads = 0;
    int min_blocks = 0;             ///< cuda megakernel occupancy hint (0: default)
    bool default_carveout = false;  ///< cuda: leave the L1/shared split to the driver
};

/// Declares --tonemap, --exposure, --max-bounces, --no-shadows, ... on `app`.
void add_render_options(CLI::App& app, RenderOverrides& o);
/// Declares --backend, --kernel, --mapping, --threads on `app`.
void add_backend_options(CLI::App& app, BackendChoice& b);
/// Applies the overrides to parameters taken from the scene.
void apply(const RenderOverrides& o, core::RenderParams& p);
/// The backend options of a choice.
rt::BackendOptions backend_options(const BackendChoice& b);

}  // namespace prt::player
