// PointRT player: options shared by prt-play and prt-bench (render-setting overrides).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

#include "prt/core/scene_view.h"
#include "prt/runtime/backend.h"
#include "prt/runtime/render_scene.h"

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
    // Surfaces (issue 9's accuracy knobs); 0 / -1 keep the core's defaults.
    std::string surface;         ///< rt::LoadOptions::surface ("" keeps the scene's)
    bool iso_float = false;      ///< rt::LoadOptions::iso_float
    float iso_samples = 0;       ///< core::IsoParams::samples
    int iso_refine = -1;         ///< core::IsoParams::refine_steps
    std::uint32_t mls_samples = 0;  ///< core::MlsParams::samples (k)
    int mls_refine = -1;            ///< core::MlsParams::refine_steps
    std::uint32_t patch_iterations = 0;  ///< core::PatchTraceParams::max_iterations
    // seed 002, 7: path tracing and samples per pixel; 0 keeps the scene's.
    bool path_tracing = false;
    std::uint32_t spp = 0;
    std::uint32_t max_depth = 0;
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
/// Declares --path-tracing, --spp, --max-depth (prt-play; prt-bench times single samples).
void add_sampling_options(CLI::App& app, RenderOverrides& o);
/// How the scene's models are loaded (--surface, --iso-float).
rt::LoadOptions load_options(const RenderOverrides& o);
/// The backend options of a choice.
rt::BackendOptions backend_options(const BackendChoice& b);

}  // namespace prt::player
