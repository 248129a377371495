// PointRT player: options shared by prt-play and prt-bench (render-setting overrides).
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "prt/core/scene_view.h"
#include "prt/error.h"
#include "prt/runtime/backend.h"
#include "prt/runtime/brick_stream.h"
#include "prt/runtime/render_scene.h"
#include "prt/tool_util.h"

// Declared, not included: CLI11 is heavy and window.cpp (through window.h) needs none of it;
// player_options.cpp, prt_play.cpp and prt_bench.cpp include prt/tool.h.
namespace CLI {
class App;
}
namespace prt::tool {
struct CommonOptions;
}

namespace prt::player {

/// Render settings a command line may override (unset = keep the scene file's).
struct RenderOverrides {
    std::string tone_map = "clamp";
    float exposure = 0;    ///< 0: keep
    int max_bounces = -1;  ///< -1: keep
    bool no_shadows = false, no_reflections = false, no_refractions = false;
    bool deep_blending = true;
    float blend_window = 1.0f;
    std::uint32_t max_steps = 1u << 16;
    std::uint32_t leaf_culling = 2;  ///< core::LeafCulling
    float lod_pixels = 1.0f;         ///< core::RenderParams::lod_pixels
    // Surfaces (issue 9's accuracy knobs); 0 / -1 keep the core's defaults.
    std::string surface;                 ///< rt::LoadOptions::surface ("" keeps the scene's)
    std::string point_colors;            ///< rt::LoadOptions::point_colors ("" keeps the materials')
    bool iso_float = false;              ///< rt::LoadOptions::iso_float
    bool bricks = false;                 ///< rt::LoadOptions::bricks
    std::string empty_space;             ///< rt::LoadOptions::empty_space ("": the default)
    float iso_samples = 0;               ///< core::IsoParams::samples
    int iso_refine = -1;                 ///< core::IsoParams::refine_steps
    std::uint32_t mls_samples = 0;       ///< core::MlsParams::samples (k)
    int mls_refine = -1;                 ///< core::MlsParams::refine_steps
    float mls_support_samples = -1.0f;   ///< core::MlsParams::samples_per_support (< 0: its default)
    std::uint32_t patch_iterations = 0;  ///< core::PatchTraceParams::max_iterations
    // seed 002, 7: path tracing and samples per pixel; 0 keeps the scene's.
    bool path_tracing = false;
    std::uint32_t spp = 0;
    std::uint32_t max_depth = 0;
};

/// A camera given on the command line (world frame); empty / 0 keeps the scene's camera or the
/// default framing.
struct CameraOverrides {
    std::string eye;      ///< "X,Y,Z"
    std::string look_at;  ///< "X,Y,Z"
    std::string up;       ///< "X,Y,Z" or "auto" (rt::RenderScene::detect_up)
    double fov = 0;       ///< vertical field of view in degrees
    bool any() const { return !eye.empty() || !look_at.empty() || !up.empty() || fov > 0; }
};

/// Camera options that contradict each other or the scene (the eye at the look-at point, an up
/// along the view): a usage error, exit status 2.
class CameraUsageError : public Error {
public:
    using Error::Error;
};

/// Backend choice.
struct BackendChoice {
    std::string name = "auto";
    std::string kernel = "mega";     ///< cuda: "mega", "mega-fifo", "mega-static" or "wavefront"
    std::string mapping = "zorder";  ///< cuda: "zorder" or "linear"
    unsigned threads = 0;
    int min_blocks = 0;             ///< cuda megakernel occupancy hint (0: default)
    bool default_carveout = false;  ///< cuda: leave the L1/shared split to the driver
    std::string iso_walk = "auto";  ///< cuda: rt::BackendOptions::cuda_iso_walk
    /// Streamed bricks (rt::BrickStream): --gpu-budget ("": the backend's default), --upload-per-frame,
    /// --frame-time (milliseconds).
    std::string gpu_budget;
    std::string upload_per_frame = "256M";
    double frame_time_ms = 50;
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
/// The streaming settings of a choice on this backend: --gpu-budget (default: the backend's
/// default_memory_budget(), CUDA: free memory minus a margin; CPU: unlimited), --upload-per-frame
/// and --frame-time. Throws prt::Error for a size that does not parse.
rt::StreamOptions stream_options(const BackendChoice& b, const rt::Backend& backend);

/// Declares --eye, --look-at, --up and --fov on `app`: values are checked as they are parsed
/// (three finite numbers, a non-zero up, 0 < fov < 180), and --eye against --look-at and --up once
/// all are read (usage errors).
void add_camera_options(CLI::App& app, CameraOverrides& c);
/// "X,Y,Z" as three finite numbers; throws CameraUsageError naming `option` otherwise.
rt::DVec3 parse_vec3(const std::string& text, const std::string& option);
/// Sets rs.scene().camera from the overrides. `framed` (a pool alone): the default view
/// (RenderScene::default_camera at the camera's width and height) with --up (default +y; auto: the
/// detected up) and --fov, then --look-at moves it (same direction and distance) and --eye places
/// it (looking at --look-at, else at the centre of the robust bounds); the default light follows
/// the camera. Otherwise the given values replace the scene camera's (--up auto: the detected up of
/// the first model). Throws CameraUsageError when the eye equals the look-at point or the up is
/// along the view. `tool` prefixes the note saying which rule chose an automatic up.
void apply_camera(const CameraOverrides& c, rt::RenderScene& rs, bool framed, bool quiet, const char* tool);

/// prt::tool::run for prt-play and prt-bench: a CameraUsageError the body throws (camera options
/// that contradict the scene) prints "NAME: error: MESSAGE (see --help)" and exits 2 like other
/// usage errors.
int run_tool(int argc, char** argv, const std::string& name, const std::string& description,
             const std::function<void(CLI::App&)>& setup,
             const std::function<void(const tool::CommonOptions&)>& body);

}  // namespace prt::player
