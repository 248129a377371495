// prt-play: the PointRT player. Loads a pool (and optionally a scene), uploads it to the chosen
// backend and renders: in a GLFW window, or headless to image files.
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <string>

#include "accumulate.h"
#include "camera_path.h"
#include "player_options.h"
#include "prt/atomic_file.h"
#include "prt/formats/scene.h"
#include "prt/runtime/backend.h"
#include "prt/runtime/brick_stream.h"
#include "prt/runtime/image.h"
#include "prt/runtime/render_scene.h"
#include "prt/tool.h"
#include "window_controls.h"
#ifdef PRT_HAVE_GLFW
#include "window.h"
#endif

namespace {

struct Options {
    std::filesystem::path pool;
    std::filesystem::path scene;
    bool headless = false;
    std::uint32_t frames = 1;
    std::string out;
    std::uint32_t width = 0, height = 0;
    double orbit = 0;
    std::filesystem::path camera_path;
    prt::player::RenderOverrides render;
    prt::player::CameraOverrides camera;
    prt::player::BackendChoice backend;
    std::filesystem::path screenshot;
    bool frames_given = false;  ///< --frames on the command line (the window then closes after them)
    bool no_interop = false;
    bool converge = false;          ///< headless: render each view until no ray falls back to a brick's LOD
    std::vector<std::string> keys;  ///< window: keys pressed by script, one per frame
    std::string save_prefix = "prt-play";  ///< window: screenshots (C) and camera paths (L)
};

/// "frame_%04d.png" -> "frame_0007.png"; names without '%' are returned unchanged.
std::string frame_name(const std::string& pattern, std::uint32_t frame) {
    if (pattern.find('%') == std::string::npos) return pattern;
    char buf[4096];
    std::snprintf(buf, sizeof(buf), pattern.c_str(), static_cast<int>(frame));
    return buf;
}

void report_frame_issues(bool quiet, const prt::rt::FrameStats& s) {
    if (s.sanitized)
        prt::tool::note(quiet, "warning: %llu non-finite pixels replaced by black",
                        static_cast<unsigned long long>(s.sanitized));
    if (s.truncated)
        prt::tool::note(quiet, "warning: %llu octree walks cut by --max-steps",
                        static_cast<unsigned long long>(s.truncated));
    if (s.dropped)
        prt::tool::note(quiet, "warning: %llu secondary rays dropped (ray stack or queue full)",
                        static_cast<unsigned long long>(s.dropped));
}

void run(const Options& o, const prt::tool::CommonOptions& common) {
    using namespace prt;
    const double t0 = tool::now_seconds();
    if (o.pool.empty() && o.scene.empty())
        throw Error("give a pool file, a --scene file, or both (see --help)");
    if (!o.out.empty()) {
        std::string why;
        if (!rt::can_write_image(frame_name(o.out, 0), &why)) throw Error(why);
        check_writable(frame_name(o.out, 0));  // before the scene loads and the frames render
    }
    if (!o.screenshot.empty()) {
#ifndef PRT_HAVE_GLFW
        throw Error("--screenshot captures the window, and this build has none (configured without GLFW)");
#endif
        if (o.headless || !o.out.empty())
            throw Error("--screenshot captures the window: it cannot be combined with --headless or --out");
        std::string ext = o.screenshot.extension().string();
        for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        if (ext == ".pfm" || ext == ".exr" || ext == ".hdr")
            throw Error(
                o.screenshot.string() +
                ": --screenshot writes 8-bit images (.ppm, .png, ...): the window holds display-encoded "
                "pixels, not linear radiance");
        std::string why;
        if (!rt::can_write_image(o.screenshot, &why)) throw Error(why);
        check_writable(o.screenshot);
    }
    rt::LoadOptions load = player::load_options(o.render);
    load.defer_bricks = true;  // rt::BrickStream loads them in core or streams them (--gpu-budget)
    rt::RenderScene rs = o.scene.empty() ? rt::RenderScene::from_pool(o.pool, load)
                                         : rt::RenderScene::load(scene::load_scene(o.scene), o.pool, load);
    scene::Camera& cam = rs.scene().camera;
    if (o.width) cam.width = o.width;
    if (o.height) cam.height = o.height;
    // A pool alone is framed at the final image size; --eye, --look-at, --up, --fov override.
    if (o.scene.empty() || o.camera.any())
        player::apply_camera(o.camera, rs, o.scene.empty(), common.quiet, "prt-play");
    player::apply(o.render, rs.params());
    for (const std::string& w : rs.warnings()) tool::note(common.quiet, "warning: %s", w.c_str());
    for (const std::string& n : rs.notes()) tool::note(common.quiet, "prt-play: %s", n.c_str());
    const double t_open = tool::now_seconds();
    auto backend = rt::make_backend(o.backend.name, player::backend_options(o.backend));
    auto stream =
        std::make_unique<rt::BrickStream>(rs, *backend, player::stream_options(o.backend, *backend));
    const rt::UploadStats up = stream->upload_stats();
    const double t_loaded = tool::now_seconds();
    tool::note(common.quiet, "prt-play: %zu model(s), %.1f MB of sections; backend %s on %s",
               rs.models().size(), rs.bytes() * 1e-6, backend->name().c_str(), backend->device().c_str());
    if (up.bytes) {
        tool::note(
            common.quiet,
            "prt-play: load %.3f s (open %.3f s, upload %.1f MB in %.3f s = %.2f GB/s, pinned async copies)",
            t_loaded - t0, t_open - t0, up.bytes * 1e-6, up.seconds, up.gb_per_s());
    } else {
        tool::note(common.quiet, "prt-play: load %.3f s (sections read in place from the mapped pool)",
                   t_loaded - t0);
    }
    if (stream->streaming())
        tool::note(
            common.quiet,
            "prt-play: streaming %u bricks: a budget of %s (always resident %s, bricks %s; in core the "
            "scene takes %s)",
            stream->brick_count(),
            tool::format_bytes(player::stream_options(o.backend, *backend).budget).c_str(),
            tool::format_bytes(stream->fixed_bytes()).c_str(),
            tool::format_bytes(stream->arena_bytes()).c_str(),
            tool::format_bytes(stream->in_core_bytes()).c_str());
    if (o.converge && !stream->streaming())
        tool::note(common.quiet,
                   "prt-play: --converge: every brick is resident (in core): one pass per frame");

    bool headless = o.headless || !o.out.empty();  // an output file means a headless run
#ifndef PRT_HAVE_GLFW
    if (!headless) tool::note(common.quiet, "prt-play: built without GLFW: rendering headless");
    headless = true;
#endif
    if (!headless) {
#ifdef PRT_HAVE_GLFW
        player::WindowOptions wo;
        wo.backend = o.backend;
        wo.quiet = common.quiet;
        wo.frames = o.frames_given || !o.screenshot.empty() ? o.frames : 0;
        wo.screenshot = o.screenshot;
        wo.interop = !o.no_interop;
        for (const std::string& k : o.keys) wo.keys.push_back(player::key_code(k));
        wo.save_prefix = o.save_prefix;
        wo.reload = [&o, load](const std::string& surface) {
            rt::LoadOptions l = load;
            l.surface = surface;
            return o.scene.empty() ? rt::RenderScene::from_pool(o.pool, l)
                                   : rt::RenderScene::load(scene::load_scene(o.scene), o.pool, l);
        };
        player::run_window(rs, backend, stream, wo);
        return;
#endif
    }

    std::vector<player::CameraKey> path;
    if (!o.camera_path.empty()) path = player::read_camera_path(o.camera_path);
    const std::string out =
        o.out.empty() ? std::string(rt::have_oiio() ? "prt-play.png" : "prt-play.ppm") : o.out;
    const bool every_frame = out.find('%') != std::string::npos;
    rt::Image image;
    rt::FrameStats total;
    // seed 002, 7: with a still camera, sampled frames (path tracing or spp > 1) accumulate: frame f
    // draws new samples and the image is the running mean of all frames, written at the end.
    const core::RenderParams base = rs.params();
    const bool still = path.empty() && o.orbit == 0.0f;
    const bool accumulate = still && !every_frame && (base.path_tracing != 0 || base.spp > 1);
    player::Accumulator acc;
    // Streaming prints a line per pass, which a progress bar would garble.
    tool::Progress progress("prt-play: rendering", o.frames,
                            common.quiet || o.frames < 2 || stream->streaming());
    std::uint64_t passes = 0, last_fallbacks = 0;
    bool stalled = false;
    for (std::uint32_t f = 0; f < o.frames; ++f) {
        scene::Camera c =
            path.empty() ? player::orbit_camera(cam, f, o.orbit) : player::path_camera(cam, path, f);
        rt::FrameRequest req;
        req.camera = rs.camera(c);
        req.params = base;
        req.params.frame = f;
        req.width = c.width;
        req.height = c.height;
        // Streaming: each pass uploads the bricks its rays asked for; --converge renders the view
        // again until no ray falls back to a brick's coarse level (then the image equals the in-core
        // render), or until nothing more can be uploaded.
        rt::FrameStats s;
        rt::Refinement refinement;
        for (std::uint32_t pass = 0;; ++pass) {
            const double t0 = tool::now_seconds();
            s = backend->render(req, image);
            ++passes;
            const rt::StreamFrame sf = stream->after_frame(s);
            if (sf.streaming)
                tool::note(common.quiet, "prt-play: frame %u%s: %.2f ms (render %.2f ms, then streaming): %s",
                           f, o.converge ? (" pass " + std::to_string(pass)).c_str() : "",
                           1e3 * (tool::now_seconds() - t0), 1e3 * s.seconds, rt::describe(sf).c_str());
            last_fallbacks = s.fallbacks;
            if (!o.converge || !sf.streaming || sf.converged()) break;
            if (!refinement.more(sf)) {
                stalled = true;
                tool::note(
                    common.quiet,
                    "prt-play: frame %u does not converge: the budget holds %u of the %u bricks the view "
                    "needs (%llu rays use a coarse level; raise --gpu-budget)",
                    f, sf.resident_bricks, sf.needed, static_cast<unsigned long long>(s.fallbacks));
                break;
            }
        }
        total += s;
        if (accumulate) acc.add(image, base);
        if (every_frame || f + 1 == o.frames) rt::write_image(frame_name(out, f), image, req.params.exposure);
        progress.update(f + 1);
    }
    progress.finish();
    const double secs = total.seconds;
    tool::note(
        common.quiet,
        "prt-play: %u frame(s) %ux%u in %.3f s (%.2f ms/frame%s), %.3g rays (%.3g primary, %.3g shadow, %.3g "
        "secondary), %.1f Mrays/s",
        o.frames, cam.width, cam.height, secs, 1e3 * secs / o.frames,
        total.device_ms > 0 ? (", GPU " + std::to_string(total.device_ms / o.frames) + " ms").c_str() : "",
        static_cast<double>(total.rays()), static_cast<double>(total.primary),
        static_cast<double>(total.shadow), static_cast<double>(total.secondary),
        secs > 0 ? total.rays() / secs * 1e-6 : 0.0);
    report_frame_issues(common.quiet, total);
    if (stream->streaming()) {
        tool::note(common.quiet, "prt-play: %llu pass(es) for %u frame(s)",
                   static_cast<unsigned long long>(passes), o.frames);
        if (last_fallbacks && !stalled)
            tool::note(
                common.quiet,
                "prt-play: %llu rays of the last frame used a brick's coarse level (--converge refines "
                "before writing)",
                static_cast<unsigned long long>(last_fallbacks));
    }
    tool::note(common.quiet, "prt-play: wrote %s",
               every_frame ? out.c_str() : frame_name(out, o.frames - 1).c_str());
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    return prt::player::run_tool(
        argc, argv, "prt-play",
        "PointRT player: ray traces (or path traces) pools on the CPU or a GPU, in a window or headless: "
        "splats (thesis ch. 2-3, 5), Implicit Surface Octrees (ch. 4), the MLS surface (Wald-Seidel 2005) "
        "or Bezier patches (seed 002), mixed in one scene.\nA pool alone renders with a default camera "
        "framing the model and one light; with "
        "--scene, the "
        "scene's camera, lights, materials and settings are used and the pool (if given) replaces the "
        "scene's models.",
        [&](CLI::App& app) {
            app.add_option(
                   "pool", o.pool,
                   "Pool file with a surface's sections (prt-octree, prt-iso, prt-mls or prt-patches)")
                ->check(prt::tool::ExistingInput);
            app.add_option("--scene", o.scene, "Scene JSON (formats/SCENE.md)")
                ->check(prt::tool::ExistingInput);
            app.add_flag(
                "--headless", o.headless,
                "Render to files without a window (implied by --out; always on in builds without GLFW)");
            app.add_option("--frames", o.frames,
                           "Frames to render headless; in the window, frames to show before it closes by "
                           "itself (default: until closed; with --screenshot, the frame captured)")
                ->check(CLI::Range(1u, 1000000u))
                ->each([&](const std::string&) { o.frames_given = true; });
            app.add_option("--screenshot", o.screenshot,
                           "Window: after --frames frames (default 1), read the displayed framebuffer back "
                           "(glReadPixels), write it to this 8-bit image (.ppm always, .png ... with "
                           "OpenImageIO) and exit");
            app.add_option("--keys", o.keys,
                           "Window: keys pressed by script, one before each of the first frames (e.g. "
                           "P,C: path tracing on, then a screenshot; names as --help-keys lists them: a "
                           "letter or digit, Esc, Home, F1, F12)")
                ->delimiter(',')
                ->check([](const std::string& k) {
                    return prt::player::key_code(k) < 0 ? "unknown key '" + k + "'" : std::string();
                });
            app.add_option("--save-prefix", o.save_prefix,
                           "Window: the C key writes screenshots to PREFIX-NNNN.png (.ppm without "
                           "OpenImageIO), the L key camera paths to PREFIX-path-NNNN.txt (the first free "
                           "numbers)");
            app.add_flag_callback(
                "--help-keys",
                [] {
                    std::fputs(prt::player::key_help().c_str(), stdout);
                    throw CLI::Success();
                },
                "Print the window's mouse and key controls and exit");
            app.add_flag(
                "--no-interop", o.no_interop,
                "Window with --backend cuda: show frames by a texture upload from host memory instead "
                "of CUDA-OpenGL interop (which needs the GL context on the CUDA device)");
            app.add_option(
                "--out", o.out,
                "Output image: .png/.exr/... (OpenImageIO builds) or .ppm/.pfm (always); default "
                "prt-play.png, "
                "or prt-play.ppm without OpenImageIO. The last frame is written; a name with a printf "
                "field (frame_%04d.png) writes every frame");
            app.add_option("--width", o.width, "Image width (0: the scene camera's, default 512)")
                ->check(CLI::Range(0u, 16384u));
            app.add_option("--height", o.height, "Image height (0: the scene camera's, default 512)")
                ->check(CLI::Range(0u, 16384u));
            app.add_option(
                "--orbit", o.orbit,
                "Headless: turn the camera about its up direction through its look-at point by this "
                "many degrees per frame");
            app.add_flag("--converge", o.converge,
                         "Headless, streamed bricks (--gpu-budget): render each frame's view again until no "
                         "ray falls back to a brick's coarse level of detail (the image then equals the "
                         "in-core one), or until the budget can take no more of the bricks it needs or 32 "
                         "passes in a row bring no fewer fallbacks (said in one line); off: one pass per "
                         "frame, refining over the frames");
            app.add_option("--camera-path", o.camera_path,
                           "Headless: camera path file, one frame per line 'px py pz lx ly lz [fov]' (world "
                           "frame; frames cycle)")
                ->check(prt::tool::ExistingInput);
            prt::player::add_camera_options(app, o.camera);
            prt::player::add_backend_options(app, o.backend);
            prt::player::add_render_options(app, o.render);
            prt::player::add_sampling_options(app, o.render);
        },
        [&](const prt::tool::CommonOptions& common) { run(o, common); });
}
