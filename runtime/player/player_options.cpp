#include "player_options.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "prt/tool.h"

namespace prt::player {

void add_render_options(CLI::App& app, RenderOverrides& o) {
    app.add_option("--tonemap", o.tone_map,
                   "Tone mapping before gamma for 8-bit output: clamp, reinhard or aces")
        ->check(CLI::IsMember({"clamp", "reinhard", "aces"}));
    app.add_option("--exposure", o.exposure,
                   "Multiply radiance by this before tone mapping (0: the scene's, default 1)")
        ->check(CLI::NonNegativeNumber);
    app.add_option("--max-bounces", o.max_bounces,
                   "Reflection/refraction depth (-1: the scene's, default 4; at most 16)")
        ->check(CLI::Range(-1, 16));
    app.add_flag("--no-shadows", o.no_shadows, "Trace no shadow rays");
    app.add_flag("--no-reflections", o.no_reflections, "Trace no reflected rays");
    app.add_flag("--no-refractions", o.no_refractions, "Trace no refracted rays");
    app.add_flag("--deep-blending,!--no-deep-blending", o.deep_blending,
                 "Blend splats across leaf borders (thesis 3.5); --no-deep-blending blends within one leaf");
    app.add_option("--blend-window", o.blend_window,
                   "Blend hits up to this many radii of the nearest splat behind it (thesis 3.3)")
        ->check(CLI::PositiveNumber);
    app.add_option("--max-steps", o.max_steps,
                   "Octree leaves one ray may visit per model (walks cut here are counted)")
        ->check(CLI::Range(1u, 1u << 30));
    app.add_option("--leaf-culling", o.leaf_culling,
                   "Pass octree leaves unread when their bounds rule out a hit: 0 off, 1 normal cones (rays "
                   "leaving a surface skip it), 2 cones and slabs. The image is the same; for comparisons")
        ->check(CLI::Range(0u, 2u));
    app.add_option(
           "--lod-pixels", o.lod_pixels,
           "Bricked pools (prt-bricks): a ray stops at an octree node whose cell is at most this many "
           "pixels wide where the ray enters it, and meets the node's level-of-detail disc instead of "
           "its splats (a streamed view then needs no brick for its far parts). 0: always the splats")
        ->check(CLI::Range(0.0f, 64.0f))
        ->capture_default_str();
    app.add_option(
           "--surface", o.surface,
           "Trace every model as this surface: splats (thesis 3), iso (thesis 4), mls (WS05), patches "
           "(seed 002) or auto (what each pool holds); default: each model's scene setting, and auto "
           "for a pool given alone")
        ->check(CLI::IsMember({"splats", "iso", "mls", "patches", "auto"}));
    app.add_option("--point-colors", o.point_colors,
                   "What multiplies the diffuse color per point, for every material (SCENE.md point_colors): "
                   "colors (the pool's), intensity (its scanner intensities as grey, 1st-99th percentile to "
                   "black..white), none, or auto (colors, else intensity, else none); default: each "
                   "material's setting, auto for a pool given alone")
        ->check(CLI::IsMember({"auto", "colors", "intensity", "none"}));
    app.add_flag(
        "--iso-float", o.iso_float,
        "ISO: trace the float leaves (160 B) instead of the quantized ones (56 B, thesis 4.4) when the "
        "pool has both");
    app.add_option("--empty-space", o.empty_space,
                   "Splat octrees and ISOs: how a ray passes empty space, for comparisons: regions (an "
                   "empty leaf is left through a box of free cells grown around it: macro-regions), boxes "
                   "(splats only: a node whose disks the ray misses is stepped over: node boxes), both, or "
                   "none; the image is the same (default: regions)")
        ->check(CLI::IsMember({"regions", "boxes", "both", "none"}));
    app.add_flag("--bricks", o.bricks,
                 "Splats: trace a pool's bricks (prt-bricks, issue 17) even when it kept its float octree "
                 "(--keep-float); a pool with bricks only always traces them (default: off)");
    app.add_option("--iso-samples", o.iso_samples,
                   "ISO: sample intervals per leaf edge of ray length (thesis 4.5; 0: the default, 4)")
        ->check(CLI::Range(0.0f, 64.0f));
    app.add_option("--iso-refine", o.iso_refine,
                   "ISO: regula falsi steps after the interpolated root (-1: the default, 2; 0: the thesis's "
                   "single interpolation)")
        ->check(CLI::Range(-1, 16));
    app.add_option("--mls-samples", o.mls_samples,
                   "MLS: samples per kd-tree cell interval, k (WS05 3.2; 0: the default, 4)")
        ->check(CLI::Range(0u, 64u));
    app.add_option(
           "--mls-refine", o.mls_refine,
           "MLS: regula falsi steps after the sign change (-1: the default, 1; 0: WS05's interpolation)")
        ->check(CLI::Range(-1, 16));
    app.add_option("--mls-support-samples", o.mls_support_samples,
                   "MLS: at least this many samples per support radius of ray length in a cell (more than k "
                   "where the ray's span through the supports is long: thin parts' two roots are not passed "
                   "between samples; -1: the default, 3; 0: k alone)")
        ->check(CLI::Range(-1.0f, 64.0f));
    app.add_option("--patch-iterations", o.patch_iterations,
                   "Patches: Newton iteration cap (seed 002, 3; 0: the default, 16)")
        ->check(CLI::Range(0u, 64u));
}

void add_sampling_options(CLI::App& app, RenderOverrides& o) {
    app.add_flag(
        "--path-tracing", o.path_tracing,
        "Path trace (seed 002, 7: diffuse bounces, perfect mirrors and glass, direct light from every "
        "light) instead of Whitted ray tracing; default: the scene's render.path_tracing (false)");
    app.add_option(
           "--spp", o.spp,
           "Samples per pixel per frame, stratified and jittered (0: the scene's render.spp, default 1)")
        ->check(CLI::Range(0u, 65536u));
    app.add_option(
           "--max-depth", o.max_depth,
           "Path tracing: the depth at which a path gathers direct light and ends (0: the default, 10)")
        ->check(CLI::Range(0u, 64u));
}

rt::LoadOptions load_options(const RenderOverrides& o) {
    rt::LoadOptions l;
    l.surface = o.surface;
    l.iso_float = o.iso_float;
    l.bricks = o.bricks;
    l.empty_space = o.empty_space;
    scene::PointColors pc{};
    if (!o.point_colors.empty() && scene::parse_point_colors(o.point_colors, pc)) l.point_colors = pc;
    return l;
}

void add_backend_options(CLI::App& app, BackendChoice& b) {
    app.add_option("--backend", b.name,
                   "cpu, cuda, hybrid (GPU and CPU share each frame) or auto (cuda if a GPU exists)")
        ->check(CLI::IsMember({"cpu", "cuda", "hybrid", "auto"}));
    app.add_option("--kernel", b.kernel,
                   "CUDA kernel structure: mega (one kernel, its warps taking 32-pixel items from a queue "
                   "until the frame is done, first the items that were slowest in the previous frame of "
                   "the same size), mega-fifo (the same queue in image order only), mega-static (one kernel, "
                   "one item per warp) or wavefront (several kernels, thesis 2.4)")
        ->check(CLI::IsMember({"mega", "mega-fifo", "mega-static", "wavefront"}));
    app.add_option("--mapping", b.mapping, "CUDA ray-to-thread mapping: zorder (thesis 2.3) or linear")
        ->check(CLI::IsMember({"zorder", "linear"}));
    app.add_option("--threads", b.threads, "CPU backend threads (0: every core the process may use)");
    app.add_option(
           "--min-blocks", b.min_blocks,
           "CUDA megakernel occupancy hint: resident 256-thread blocks per SM, 1-6, which caps registers "
           "per thread (0: the measured default of the frame's kernel: 3 for splats, bricked splats and "
           "ISO, 2 for patches and MLS, 4 for the general kernel of mixed surfaces, several samples per "
           "pixel or path tracing, its only variant; the patch kernel has variants 1, 2 and 4). Values "
           "other than the defaults need a build with -DPRT_CUDA_TUNING_KERNELS=ON")
        ->check(CLI::Range(0, 6));
    app.add_flag("--default-carveout", b.default_carveout,
                 "CUDA: leave the L1 / shared-memory split to the driver instead of preferring L1");
    app.add_option("--iso-walk", b.iso_walk,
                   "CUDA, ISO with macro-regions (--empty-space regions): auto (the first frames of each "
                   "kind time the walk through the regions and the walk compiled without region code, "
                   "and keep the faster, timing the other every 64th frame), regions or plain. The image "
                   "is the same")
        ->check(CLI::IsMember({"auto", "regions", "plain"}))
        ->capture_default_str();
    app.add_option("--gpu-budget", b.gpu_budget,
                   "Memory the scene may take (bytes, or with K/M/G/T: 512M, 1.5G; 'unlimited'): a bricked "
                   "pool (prt-bricks) larger than this streams its bricks, least recently used ones "
                   "evicted, rays reaching a missing brick using its coarse level of detail meanwhile. "
                   "Default: the GPU's free memory minus 512 MiB on cuda; unlimited on cpu (the pool is "
                   "read in place from the mapped file), where a budget streams into host memory");
    app.add_option("--upload-per-frame", b.upload_per_frame,
                   "Streaming: brick bytes uploaded at most after each frame, so frames stay short (at "
                   "least one brick; K/M/G suffixes)")
        ->default_val("256M");
    app.add_option(
           "--frame-time", b.frame_time_ms,
           "Streaming: uploads after a frame stop once the frame (its render, then the uploads) has "
           "taken this many milliseconds, the other bricks waiting for the next frames, so a view "
           "that turns to bricks not yet resident refines over several short frames (a render longer than "
           "that, as on the CPU, leaves the uploads a quarter of its time; at least one brick is "
           "uploaded; 0: no time limit)")
        ->default_val(50.0)
        ->check(CLI::Range(0.0, 1e6));
}

rt::StreamOptions stream_options(const BackendChoice& b, const rt::Backend& backend) {
    rt::StreamOptions s;
    if (b.gpu_budget.empty())
        s.budget = backend.default_memory_budget();
    else if (b.gpu_budget == "unlimited")
        s.budget = 0;
    else {
        s.budget = tool::parse_byte_size(b.gpu_budget, "--gpu-budget");  // 0 is refused
    }
    s.upload_per_frame = tool::parse_byte_size(b.upload_per_frame, "--upload-per-frame");
    s.frame_seconds = 1e-3 * b.frame_time_ms;
    return s;
}

void apply(const RenderOverrides& o, core::RenderParams& p) {
    p.tone_map = o.tone_map == "reinhard" ? core::ToneMap::reinhard
                 : o.tone_map == "aces"   ? core::ToneMap::aces
                                          : core::ToneMap::clamp;
    if (o.exposure > 0) p.exposure = o.exposure;
    if (o.max_bounces >= 0) p.max_bounces = static_cast<std::uint32_t>(o.max_bounces);
    if (o.no_shadows) p.shadows = 0;
    if (o.no_reflections) p.reflections = 0;
    if (o.no_refractions) p.refractions = 0;
    if (o.path_tracing) p.path_tracing = 1;
    if (o.spp > 0) p.spp = o.spp;
    if (o.max_depth > 0) p.max_path_depth = o.max_depth;
    if (o.iso_samples > 0) p.iso.samples = o.iso_samples;
    if (o.iso_refine >= 0) p.iso.refine_steps = static_cast<std::uint32_t>(o.iso_refine);
    if (o.mls_samples >= 2) p.mls.samples = o.mls_samples;
    if (o.mls_refine >= 0) p.mls.refine_steps = static_cast<std::uint32_t>(o.mls_refine);
    if (o.mls_support_samples >= 0.0f) p.mls.samples_per_support = o.mls_support_samples;
    if (o.patch_iterations > 0) p.patch.max_iterations = o.patch_iterations;
    p.deep_blending = o.deep_blending ? 1u : 0u;
    p.blend_window = o.blend_window;
    p.max_steps = o.max_steps;
    p.leaf_culling = o.leaf_culling;
    p.lod_pixels = o.lod_pixels;
}

rt::BackendOptions backend_options(const BackendChoice& b) {
    rt::BackendOptions o;
    o.cpu_threads = b.threads;
    o.cuda_wavefront = b.kernel == "wavefront";
    o.cuda_persistent = b.kernel != "mega-static";
    o.cuda_heavy_first = b.kernel == "mega";
    o.cuda_linear_mapping = b.mapping == "linear";
    o.cuda_min_blocks = b.min_blocks;
    o.cuda_max_l1 = !b.default_carveout;
    o.cuda_iso_walk = b.iso_walk;
    return o;
}

namespace {

double vdot(const rt::DVec3& a, const rt::DVec3& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
rt::DVec3 vsub(const rt::DVec3& a, const rt::DVec3& b) {
    return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
rt::DVec3 vcross(const rt::DVec3& a, const rt::DVec3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double vlen(const rt::DVec3& a) {
    return std::sqrt(vdot(a, a));
}
std::string vtext(const rt::DVec3& v) {
    std::ostringstream s;
    s << v[0] << "," << v[1] << "," << v[2];
    return s.str();
}

/// The checks SCENE.md makes on a camera (formats/src/scene.cpp): the eye is not the look-at point,
/// and the up is non-zero and not within ~1e-6 radians of the view direction.
void check_camera(const scene::Camera& c, const std::string& what) {
    const rt::DVec3 view = vsub(c.look_at, c.position);
    if (vlen(view) == 0)
        throw CameraUsageError(what + ": the eye " + vtext(c.position) + " equals the look-at point");
    if (!(vlen(c.up) > 0)) throw CameraUsageError(what + ": the up direction is the zero vector");
    if (vlen(vcross(view, c.up)) <= 1e-6 * vlen(view) * vlen(c.up))
        throw CameraUsageError(what + ": the up direction " + vtext(c.up) +
                               " is parallel to the view direction " + vtext(view));
}

}  // namespace

rt::DVec3 parse_vec3(const std::string& text, const std::string& option_name) {
    const std::string option = option_name.empty() ? std::string() : option_name + ": ";
    rt::DVec3 v{};
    std::size_t start = 0;
    for (int i = 0; i < 3; ++i) {
        const std::size_t comma = text.find(',', start);
        if ((i < 2) != (comma != std::string::npos))
            throw CameraUsageError(option + "expected X,Y,Z (three numbers, commas between), got '" + text +
                                   "'");
        const std::string part = text.substr(start, i < 2 ? comma - start : std::string::npos);
        char* end = nullptr;
        v[i] = std::strtod(part.c_str(), &end);
        if (part.empty() || end == part.c_str() || *end != '\0' || !std::isfinite(v[i]))
            throw CameraUsageError(option + "'" + part + "' in '" + text + "' is not a finite number");
        start = comma + 1;
    }
    return v;
}

void add_camera_options(CLI::App& app, CameraOverrides& c) {
    auto vec3 = [](bool allow_auto) {
        return CLI::Validator(
            [allow_auto](std::string& s) -> std::string {
                if (allow_auto && s == "auto") return {};
                try {
                    const rt::DVec3 v = parse_vec3(s, "");
                    if (allow_auto && vlen(v) == 0) return "the up direction is the zero vector";
                } catch (const Error& e) {
                    return e.what();
                }
                return {};
            },
            allow_auto ? "X,Y,Z|auto" : "X,Y,Z");
    };
    app.add_option(
           "--eye", c.eye,
           "Camera position, world frame (replaces the scene camera's; a pool alone: the camera looks "
           "at --look-at, else at the centre of the model)")
        ->check(vec3(false));
    app.add_option(
           "--look-at", c.look_at,
           "Point at the image centre, world frame (a pool alone without --eye: the default view moved "
           "to look at it)")
        ->check(vec3(false));
    app.add_option("--up", c.up,
                   "The image's up direction, world frame, or auto: detected from the data (the normal of a "
                   "plane holding >= 20 % of the points, signed toward the sensors, else toward what "
                   "stands on it; else the normal of the plane the scanners' directions span; else +y; the "
                   "rule that decided is printed). Default: the scene camera's, +y for a pool alone (the "
                   "default view turns to the up given)")
        ->check(vec3(true));
    app.add_option("--fov", c.fov,
                   "Vertical field of view in degrees, 0 < fov < 180 (0: the scene's, default 45)")
        ->check(CLI::Validator(
            [](std::string& s) -> std::string {
                char* end = nullptr;
                const double v = std::strtod(s.c_str(), &end);
                if (s.empty() || *end != '\0' || !std::isfinite(v) || v < 0 || v >= 180)
                    return "expected degrees in (0, 180), got '" + s + "'";
                return {};
            },
            "DEG"));
    // The checks that need several options together, once all are parsed (usage errors too).
    app.final_callback([&c]() {
        try {
            if (!c.eye.empty() && !c.look_at.empty()) {
                scene::Camera cam;
                cam.position = parse_vec3(c.eye, "--eye");
                cam.look_at = parse_vec3(c.look_at, "--look-at");
                cam.up = !c.up.empty() && c.up != "auto" ? parse_vec3(c.up, "--up") : rt::DVec3{0, 1, 0};
                if (c.up.empty() || c.up == "auto") {
                    if (vlen(vsub(cam.look_at, cam.position)) == 0)
                        throw CameraUsageError("--eye " + c.eye + " equals --look-at");
                } else {
                    check_camera(cam, "--eye, --look-at, --up");
                }
            }
        } catch (const CameraUsageError& e) {
            throw CLI::ValidationError(e.what());
        }
    });
}

void apply_camera(const CameraOverrides& o, rt::RenderScene& rs, bool framed, bool quiet, const char* tool) {
    scene::Camera& cam = rs.scene().camera;
    std::optional<rt::DVec3> up;
    std::string rule;  // printed once the camera is known to be valid (an error stays one line)
    if (o.up == "auto") {
        const rt::UpDetection d = rs.detect_up();
        rule = rt::direction_name(d.up) + ": " + d.description;
        up = d.up;
    } else if (!o.up.empty()) {
        up = parse_vec3(o.up, "--up");
    }
    const double fov = o.fov > 0 ? o.fov : (framed ? 45.0 : cam.fov_y_degrees);
    if (framed) {
        // The default view at the final image size, turned to the up and fov asked for.
        const std::uint32_t w = cam.width, h = cam.height;
        cam = rs.default_camera(w, h, up.value_or(rt::DVec3{0, 1, 0}), fov);
        if (!o.look_at.empty()) {
            const rt::DVec3 target = parse_vec3(o.look_at, "--look-at");
            const rt::DVec3 back = vsub(cam.position, cam.look_at);
            cam.look_at = target;
            cam.position = {target[0] + back[0], target[1] + back[1], target[2] + back[2]};
        }
        if (!o.eye.empty()) {
            cam.position = parse_vec3(o.eye, "--eye");
            if (o.look_at.empty()) {  // the centre of the model's robust bounds
                const rt::Box& b = rs.robust_bounds();
                cam.look_at = {0.5 * (b.lo[0] + b.hi[0]), 0.5 * (b.lo[1] + b.hi[1]),
                               0.5 * (b.lo[2] + b.hi[2])};
            }
        }
    } else {
        if (!o.eye.empty()) cam.position = parse_vec3(o.eye, "--eye");
        if (!o.look_at.empty()) cam.look_at = parse_vec3(o.look_at, "--look-at");
        if (up) cam.up = *up;
        cam.fov_y_degrees = fov;
    }
    if (o.any()) {
        std::string what;
        for (const auto& [given, name] :
             {std::pair{!o.eye.empty(), "--eye"}, std::pair{!o.look_at.empty(), "--look-at"},
              std::pair{!o.up.empty(), "--up"}}) {
            if (given) what += (what.empty() ? "" : ", ") + std::string(name);
        }
        if (!o.eye.empty() && o.look_at.empty())
            what += framed ? " (looking at the model's centre)"
                           : " (looking at the scene camera's look-at point)";
        if (o.up == "auto") what += " (detected " + rt::direction_name(*up) + ")";
        check_camera(cam, what.empty() ? std::string("--fov") : what);
    }
    if (!rule.empty()) tool::note(quiet, "%s: --up auto: %s", tool, rule.c_str());
    if (framed) rs.place_default_light();
}

int run_tool(int argc, char** argv, const std::string& name, const std::string& description,
             const std::function<void(CLI::App&)>& setup,
             const std::function<void(const tool::CommonOptions&)>& body) {
    bool usage_error = false;
    const int code = tool::run(
        argc, argv, name, description, [&](CLI::App& app, tool::CommonOptions&) { setup(app); },
        [&](const tool::CommonOptions& common) {
            try {
                body(common);
            } catch (const CameraUsageError& e) {
                std::fprintf(stderr, "%s: error: %s (see --help)\n", name.c_str(), e.what());
                usage_error = true;
            }
        });
    return usage_error ? k_exit_usage_error : code;
}

}  // namespace prt::player
