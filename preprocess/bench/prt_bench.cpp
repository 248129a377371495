// prt-bench: rays per second by ray kind and frames per second (issue 4 targets: on one H100,
// 1M-point model, 1024x1024: primary >= 1 Grays/s, one shadow light >= 0.8 Grays/s, 4-bounce
// reflections >= 0.5 Grays/s). GPU frames are timed with CUDA events (kernels only, no download)
// after warm-up; CPU frames with the host clock; the median over --frames frames is reported, as a
// table on stdout and optionally as JSON.
//
// Without a pool, a synthetic scene is built in memory: prt-synth's room (a closed box seen from
// inside with a sphere and a cube) sampled with N points, splat radii from the sampling density
// (the k-NN radius of thesis 3.1 for uniform density, k = 9), and prt-octree's builder. The
// camera sits inside the room, so every primary ray hits something.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench_scene.h"
#include "camera_path.h"
#include "player_options.h"
#include "prt/atomic_file.h"
#include "prt/runtime/backend.h"
#include "prt/runtime/brick_stream.h"
#include "prt/runtime/render_scene.h"
#include "prt/tool.h"
#include "ray_profile.h"

namespace {

constexpr const char* k_description =
    "PointRT benchmark: rays per second by ray kind and frames per second for three scenarios (primary; "
    "one "
    "shadow light; 4-bounce reflections), median over frames after warm-up (CUDA events on the GPU). "
    "Without a "
    "pool or scene it renders a synthetic room of --synthetic points from inside.";

using namespace prt;

struct Options {
    player::BenchSceneOptions scene;
    std::uint32_t frames = 100, warmup = 10;
    std::string json;
    std::string scenarios = "primary,shadow,reflect4";
    bool profile = false;
    double orbit = 0;  ///< degrees the camera turns a frame (0: a still camera)
    player::BackendChoice backend;
    player::RenderOverrides render;
    player::CameraOverrides camera;
};

/// Work per ray of one ray kind, derived from two scenarios: (work of `with` - work of `base`) /
/// (rays of `with` - rays of `base`). The primary rays of every scenario are the same, so the
/// shadow and reflect4 scenarios minus the primary one give the shadow and secondary rays' work.
nlohmann::json derived_kind(const rt::FrameStats& with, const rt::FrameStats& base) {
    const double rays = static_cast<double>(with.rays()) - static_cast<double>(base.rays());
    if (!(rays > 0)) return nullptr;
    auto per = [&](std::uint64_t a, std::uint64_t b) {
        return (static_cast<double>(a) - static_cast<double>(b)) / rays;
    };
    return {{"leaves_per_ray", per(with.leaves, base.leaves)},
            {"culled_leaves_per_ray", per(with.culled, base.culled)},
            {"splat_tests_per_ray", per(with.splat_tests, base.splat_tests)}};
}

/// Streamed bricks (--gpu-budget): renders the view until no ray falls back to a brick's coarse
/// level or no pass brings fewer fallbacks (rt::Refinement; at most 100000 passes), one stderr line per pass;
/// returns the refinement's numbers as JSON and prints them on one stdout line.
nlohmann::json refine(const tool::CommonOptions& common, rt::Backend& backend, rt::BrickStream& stream,
                      const rt::FrameRequest& req, rt::Image& image, const std::string& name) {
    nlohmann::json passes = nlohmann::json::array();
    std::uint64_t uploaded = 0, bytes = 0;
    double upload_s = 0;
    const double t0 = tool::now_seconds();
    rt::StreamFrame f;
    rt::Refinement refinement;
    for (std::uint32_t pass = 0; pass < 100000; ++pass) {
        const rt::FrameStats s = backend.render(req, image);
        f = stream.after_frame(s);
        tool::note(common.quiet, "prt-bench: %s: refining, pass %u: %s", name.c_str(), pass,
                   rt::describe(f).c_str());
        uploaded += f.uploaded;
        bytes += f.uploaded_bytes;
        upload_s += f.upload_seconds;
        passes.push_back({{"resident_bytes", f.resident_bytes},
                          {"resident_bricks", f.resident_bricks},
                          {"bricks_uploaded", f.uploaded},
                          {"uploaded_bytes", f.uploaded_bytes},
                          {"upload_gb_per_s", f.gb_per_s()},
                          {"check_ms", f.prepare_seconds * 1e3},
                          {"copy_ms", f.copy_seconds * 1e3},
                          {"evicted", f.evicted},
                          {"fallback_rays", f.fallback_rays},
                          {"frame_ms", s.seconds * 1e3}});
        if (!refinement.more(f)) break;
    }
    const double secs = tool::now_seconds() - t0;
    const double gbs = upload_s > 0 ? bytes / upload_s * 1e-9 : 0.0;
    std::printf(
        "%-10s streaming: %s after %zu pass(es), %.3f s: %llu bricks uploaded (%s, %.2f GB/s), %u of %u "
        "bricks resident (%s)%s\n",
        name.c_str(), f.converged() ? "converged" : "not converged", passes.size(), secs,
        static_cast<unsigned long long>(uploaded), tool::format_bytes(bytes).c_str(), gbs, f.resident_bricks,
        f.brick_count, tool::format_bytes(f.resident_bytes).c_str(),
        f.converged() ? ""
                      : (", the budget holds too few of the " + std::to_string(f.needed) +
                         " bricks the view needs; timed frames use coarse levels")
                            .c_str());
    return {{"converged", f.converged()},
            {"passes", passes.size()},
            {"seconds", secs},
            {"bricks_uploaded", uploaded},
            {"uploaded_bytes", bytes},
            {"upload_gb_per_s", gbs},
            {"resident_bytes", f.resident_bytes},
            {"resident_bricks", f.resident_bricks},
            {"brick_count", f.brick_count},
            {"needed_bricks", f.needed},
            {"per_pass", passes}};
}

/// Times one scenario (`o.frames` frames after `o.warmup`): prints its row, appends its JSON to
/// `report` and returns the last frame's counters. Streamed bricks refine first (refine()); the
/// timed frames then go on streaming (after_frame after each).
rt::FrameStats time_scenario(const Options& o, const tool::CommonOptions& common, rt::Backend& backend,
                             rt::BrickStream& stream, const rt::RenderScene& rs,
                             const player::BenchScenario& sc, const std::vector<core::Material>& original,
                             nlohmann::json& report) {
    // Materials of the scenario (the mirror world of reflect4), uploaded before timing.
    const std::vector<core::Material> mats = player::scenario_materials(sc, original);
    core::SceneView view = rs.view();
    view.materials = mats.data();
    stream.set_scene(view);
    rt::FrameRequest req;
    req.camera = rs.camera();
    req.params = sc.params;
    req.width = o.scene.width;
    req.height = o.scene.height;
    req.download = false;
    rt::Image image;
    image.resize(o.scene.width, o.scene.height);
    nlohmann::json streaming;
    if (stream.streaming()) streaming = refine(common, backend, stream, req, image, sc.name);
    // --orbit: every frame (warm-up ones too) turns the camera on from the last.
    auto turn = [&](std::uint32_t frame) {
        if (o.orbit != 0.0) req.camera = rs.camera(player::orbit_camera(rs.scene().camera, frame, o.orbit));
    };
    for (std::uint32_t i = 0; i < o.warmup; ++i) {
        turn(i);
        stream.after_frame(backend.render(req, image));
    }
    std::vector<double> ms, wall_ms;
    rt::FrameStats last;
    std::vector<std::uint64_t> heavy_items;  // per timed frame: items the queue handed out first
    tool::Progress progress("prt-bench: " + sc.name, o.frames, common.quiet);
    for (std::uint32_t i = 0; i < o.frames; ++i) {
        turn(o.warmup + i);
        last = backend.render(req, image);
        stream.after_frame(last);  // streamed bricks: uploads between frames are not timed
        heavy_items.push_back(last.heavy_first);
        // CUDA: kernel time from events; CPU and hybrid: the frame's wall time.
        ms.push_back(backend.name() == "cuda" ? last.device_ms : last.seconds * 1e3);
        wall_ms.push_back(last.seconds * 1e3);  // every backend: to compare cuda with hybrid
        progress.update(i + 1);
    }
    progress.finish();
    const double med = player::median(ms);
    const double grays = med > 0 ? last.rays() / (med * 1e-3) * 1e-9 : 0;
    const double rays = last.rays() ? static_cast<double>(last.rays()) : 1.0;
    std::printf("%-10s %10.3f %8.1f %12llu %12llu %12llu %12llu %10.3f %8.2f %8.2f %8.2f\n", sc.name.c_str(),
                med, 1e3 / med, static_cast<unsigned long long>(last.rays()),
                static_cast<unsigned long long>(last.primary), static_cast<unsigned long long>(last.shadow),
                static_cast<unsigned long long>(last.secondary), grays, sc.target_grays, last.leaves / rays,
                last.splat_tests / rays);
    report.push_back({{"name", sc.name},
                      {"what", sc.what},
                      {"median_ms", med},
                      {"min_ms", *std::min_element(ms.begin(), ms.end())},
                      {"max_ms", *std::max_element(ms.begin(), ms.end())},
                      {"fps", 1e3 / med},
                      {"rays_per_frame", last.rays()},
                      {"primary", last.primary},
                      {"shadow", last.shadow},
                      {"secondary", last.secondary},
                      {"grays_per_s", grays},
                      {"primary_grays_per_s", last.primary / (med * 1e-3) * 1e-9},
                      {"shadow_grays_per_s", last.shadow / (med * 1e-3) * 1e-9},
                      {"secondary_grays_per_s", last.secondary / (med * 1e-3) * 1e-9},
                      {"heavy_first_items", last.heavy_first},
                      {"heavy_first_frames", std::count_if(heavy_items.begin(), heavy_items.end(),
                                                           [](std::uint64_t n) { return n != 0; })},
                      {"frames_ms", ms},
                      {"frames_heavy_first_items", heavy_items},
                      {"leaves_per_ray", last.rays() ? double(last.leaves) / last.rays() : 0.0},
                      {"culled_leaves_per_ray", last.rays() ? double(last.culled) / last.rays() : 0.0},
                      {"splat_tests_per_ray", last.rays() ? double(last.splat_tests) / last.rays() : 0.0},
                      {"truncated", last.truncated},
                      {"sanitized", last.sanitized},
                      {"brick_fallbacks", last.fallbacks},  // rays that used a brick's coarse level
                      {"streaming", streaming},
                      {"timer", backend.name() == "cuda" ? "cuda events" : "host clock"},
                      {"wall_median_ms", player::median(wall_ms)},
                      {"gpu_share", last.gpu_share},
                      {"target_grays_per_s", sc.target_grays},
                      {"meets_target", grays >= sc.target_grays}});
    return last;
}

/// Work per ray by kind (the shadow and reflect4 scenarios minus the primary one).
void report_ray_kinds(const std::vector<std::pair<std::string, rt::FrameStats>>& done,
                      nlohmann::json& report) {
    const auto find = [&](const std::string& name) -> const rt::FrameStats* {
        for (const auto& d : done)
            if (d.first == name) return &d.second;
        return nullptr;
    };
    if (const rt::FrameStats* p = find("primary")) {
        nlohmann::json kinds;
        kinds["primary"] = derived_kind(*p, rt::FrameStats{});
        if (const rt::FrameStats* s = find("shadow")) kinds["shadow"] = derived_kind(*s, *p);
        if (const rt::FrameStats* r = find("reflect4")) kinds["secondary"] = derived_kind(*r, *p);
        report["per_ray_kind"] = kinds;
        std::printf("per ray kind (leaves visited / filled leaves passed by their bounds / splat tests):");
        for (const char* k : {"primary", "shadow", "secondary"}) {
            if (!kinds.contains(k) || kinds[k].is_null()) continue;
            std::printf(" %s %.1f / %.1f / %.1f;", k, kinds[k]["leaves_per_ray"].get<double>(),
                        kinds[k]["culled_leaves_per_ray"].get<double>(),
                        kinds[k]["splat_tests_per_ray"].get<double>());
        }
        std::printf("\n");
    }
}

/// Host-side profile of the shadow and reflect4 scenarios: work by bounce depth, SIMT efficiency.
void profile_scenarios(const Options& o, const rt::RenderScene& rs,
                       const std::vector<player::BenchScenario>& all,
                       const std::vector<core::Material>& original, nlohmann::json& report) {
    for (const player::BenchScenario& sc : all) {
        if (sc.name == "primary" || o.scenarios.find(sc.name) == std::string::npos) continue;
        const std::vector<core::Material> mats = player::scenario_materials(sc, original);
        core::SceneView view = rs.view();
        view.materials = mats.data();
        view.params = sc.params;
        const player::RayProfile prof =
            player::profile_rays(view, rs.camera(), o.scene.width, o.scene.height);
        std::printf("profile of %s (host, the core's functions):\n%s", sc.name.c_str(), prof.table().c_str());
        report["profile"][sc.name] = prof.to_json();
    }
}

void run(Options o, const tool::CommonOptions& common) {
    if (!o.json.empty()) check_writable(o.json);  // refused before the (long) benchmark runs
    if (!o.scene.save_pool.empty()) check_writable(o.scene.save_pool);
    o.scene.load = player::load_options(o.render);
    o.scene.load.defer_bricks = true;  // rt::BrickStream loads them in core or streams them (--gpu-budget)
    rt::RenderScene rs = player::bench_scene(o.scene, common.quiet);
    // A pool alone is framed at the benchmark's image size; --eye, --look-at, --up, --fov override.
    const bool framed = !o.scene.pool.empty() && o.scene.scene.empty();
    if (framed || o.camera.any()) player::apply_camera(o.camera, rs, framed, common.quiet, "prt-bench");
    for (const std::string& n : rs.notes()) tool::note(common.quiet, "prt-bench: %s", n.c_str());
    core::RenderParams base = rs.params();
    player::apply(o.render, base);

    auto backend = rt::make_backend(o.backend.name, player::backend_options(o.backend));
    const double t0 = tool::now_seconds();
    const rt::StreamOptions stream_options = player::stream_options(o.backend, *backend);
    rt::BrickStream stream(rs, *backend, stream_options);
    const rt::UploadStats up = stream.upload_stats();
    const double load_s = tool::now_seconds() - t0;

    const std::vector<player::BenchScenario> all = player::bench_scenarios(base);
    const std::vector<core::Material> original(rs.view().materials,
                                               rs.view().materials + rs.view().material_count);

    nlohmann::json report;
    report["device"] = backend->device();
    report["backend"] = backend->name();
    report["kernel"] = o.backend.kernel;
    report["orbit_degrees_per_frame"] = o.orbit;
    report["mapping"] = o.backend.mapping;
    report["min_blocks"] = o.backend.min_blocks;
    report["leaf_culling"] = base.leaf_culling;
    report["max_leaf"] = o.scene.max_leaf;
    report["width"] = o.scene.width;
    report["height"] = o.scene.height;
    report["frames"] = o.frames;
    report["warmup"] = o.warmup;
    std::uint64_t splats = 0, points = 0, leaves = 0;
    for (const auto& m : rs.models()) {
        splats += m.view.octree.splat_count;
        points += m.view.point_count;
        leaves += m.view.octree.filled_leaves;
        const core::BrickView& b = m.view.bricks;  // a bricked pool (issue 17): its bricks' counts
        for (std::uint32_t i = 0; b.top_nodes != nullptr && i < b.brick_count; ++i)
            splats += b.table[i].splat_count, leaves += b.table[i].leaf_count;
    }
    report["model"] = {
        {"points", points}, {"splats", splats}, {"filled_leaves", leaves}, {"bytes", rs.bytes()}};
    report["load"] = {{"seconds", load_s},
                      {"upload_bytes", up.bytes},
                      {"upload_seconds", up.seconds},
                      {"upload_gb_per_s", up.gb_per_s()}};
    report["streaming"] = {{"streamed", stream.streaming()},
                           {"budget_bytes", stream_options.budget},
                           {"in_core_bytes", stream.in_core_bytes()},
                           {"always_resident_bytes", stream.streaming() ? stream.fixed_bytes() : rs.bytes()},
                           {"arena_bytes", stream.arena_bytes()},
                           {"bricks", stream.brick_count()}};
    if (stream.streaming())
        std::printf(
            "prt-bench: streaming %u bricks under a budget of %s (always resident %s, bricks %s; in core "
            "%s)\n",
            stream.brick_count(), tool::format_bytes(stream_options.budget).c_str(),
            tool::format_bytes(stream.fixed_bytes()).c_str(),
            tool::format_bytes(stream.arena_bytes()).c_str(),
            tool::format_bytes(stream.in_core_bytes()).c_str());
    std::printf(
        "prt-bench: %s on %s, %ux%u, %llu points (%llu splats, %llu filled leaves), leaf culling %u, median "
        "of %u "
        "frames after %u warm-up\n",
        backend->name().c_str(), backend->device().c_str(), o.scene.width, o.scene.height,
        static_cast<unsigned long long>(points), static_cast<unsigned long long>(splats),
        static_cast<unsigned long long>(leaves), base.leaf_culling, o.frames, o.warmup);
    std::printf("%-10s %10s %8s %12s %12s %12s %12s %10s %8s %8s %8s\n", "scenario", "ms/frame", "fps",
                "rays/frame", "primary", "shadow", "secondary", "Grays/s", "target", "leaves", "tests");
    std::vector<std::pair<std::string, rt::FrameStats>> done;
    for (const player::BenchScenario& sc : all) {
        if (o.scenarios.find(sc.name) == std::string::npos) continue;
        done.emplace_back(sc.name,
                          time_scenario(o, common, *backend, stream, rs, sc, original, report["scenarios"]));
    }
    report_ray_kinds(done, report);
    if (o.profile) profile_scenarios(o, rs, all, original, report);
    if (!o.json.empty()) write_file_atomic(o.json, report.dump(2) + "\n");
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    return prt::player::run_tool(
        argc, argv, "prt-bench", k_description,
        [&](CLI::App& app) {
            player::add_scene_options(
                app, o.scene, "Pool with the octree sections (default: the synthetic room)",
                "Synthetic room: splats per octree leaf before a split (thesis 3.2's X)", true);
            app.add_option("--frames", o.frames, "Timed frames per scenario (the median is reported)")
                ->check(CLI::Range(1u, 100000u));
            app.add_option("--warmup", o.warmup, "Untimed frames before timing")
                ->check(CLI::Range(0u, 100000u));
            app.add_option("--scenarios", o.scenarios,
                           "Comma-separated subset of primary, shadow, reflect4 and full4 (shadows + 4 "
                           "bounces; not in the default)");
            app.add_option("--json", o.json, "Write the results as JSON to this file");
            app.add_option("--orbit", o.orbit,
                           "Turn the camera about its up direction through its look-at point by this many "
                           "degrees every frame, warm-up frames included (a moving camera; 0: still)");
            app.add_flag("--profile", o.profile,
                         "Also trace the shadow and reflect4 frames on the host, recording each ray's work: "
                         "leaves, leaves passed by their bounds and splat tests per ray by bounce depth, and "
                         "the SIMT efficiency of 32-pixel warps (slow: every core of this machine)");
            prt::player::add_camera_options(app, o.camera);
            prt::player::add_backend_options(app, o.backend);
            prt::player::add_render_options(app, o.render);
        },
        [&](const prt::tool::CommonOptions& common) { run(o, common); });
}
