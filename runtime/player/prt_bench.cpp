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
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "octree_build.h"
#include "player_options.h"
#include "point_cloud.h"
#include "prt/formats/pool.h"
#include "prt/runtime/backend.h"
#include "prt/runtime/render_scene.h"
#include "prt/tool.h"
#include "synth.h"

namespace {

using namespace prt;

struct Options {
    std::filesystem::path pool;
    std::filesystem::path scene;
    std::uint64_t synthetic = 1000000;
    std::uint32_t max_leaf = 32;  // measured best for primary rays on the H200 (16: -14%, 64: -7%)
    std::filesystem::path save_pool;
    std::uint32_t width = 1024, height = 1024;
    std::uint32_t frames = 100, warmup = 10;
    std::string json;
    std::string scenarios = "primary,shadow,reflect4";
    player::BackendChoice backend;
    player::RenderOverrides render;
};

/// The synthetic benchmark pool: prt-synth room + density radii + prt-octree, validated.
std::shared_ptr<const pool::PoolFile> synthetic_pool(std::uint64_t n, std::uint32_t max_leaf,
                                                     const std::filesystem::path& save, bool quiet) {
    synth::SynthOptions so;
    so.shape.kind = synth::ShapeKind::room;
    so.shape.room = synth::Room::standard(2.0);
    so.count = n;
    so.colors = synth::ColorMode::parts;
    synth::SynthResult sr = synth::synthesize(so);
    // thesis 3.1: radius = distance to the k-th neighbour; for uniform density n/A that distance
    // is about sqrt(k A / (pi n)).
    const double area = synth::surface_area(so.shape);
    const float r =
        static_cast<float>(std::sqrt(9.0 * area / (3.14159265358979323846 * static_cast<double>(n))));
    sr.cloud.radii.assign(sr.cloud.size(), r);
    pool::PoolWriter w;
    pre::write_point_sections(sr.cloud, w);
    auto points =
        std::make_shared<pool::PoolFile>(pool::PoolFile::from_bytes(w.serialize(), "synthetic room"));
    pre::OctreeStats stats;
    pre::OctreeParams params;
    params.max_leaf_splats = max_leaf;
    pre::SplatOctree tree =
        pre::build_octree(points->require<pool::Float3>(pool::SectionType::positions, "prt-bench"),
                          points->require<pool::Float3>(pool::SectionType::normals, "prt-bench"),
                          points->require<float>(pool::SectionType::radii, "prt-bench"), params, &stats);
    pool::PoolWriter w2;
    w2.carry_over(*points);
    pre::add_octree_sections(std::move(tree), w2);
    w2.add_provenance("prt-bench", PRT_VERSION,
                      "{\"synthetic\": \"room\", \"points\": " + std::to_string(n) + "}");
    tool::note(quiet,
               "prt-bench: synthetic room: %llu points, radius %.4g, octree depth %u, %u nodes, %llu splats "
               "stored (x%.2f), %.2f s",
               static_cast<unsigned long long>(n), r, stats.depth, stats.nodes,
               static_cast<unsigned long long>(stats.stored_splats), stats.replication_factor, stats.seconds);
    if (!save.empty()) {
        w2.write(save);
        tool::note(quiet, "prt-bench: wrote %s", save.string().c_str());
    }
    return std::make_shared<const pool::PoolFile>(
        pool::PoolFile::from_bytes(w2.serialize(), "synthetic room"));
}

struct Scenario {
    std::string name;
    std::string what;
    core::RenderParams params;
    bool mirror = false;  ///< every material becomes a mirror (reflectivity 0.8)
    double target_grays = 0;
};

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    const std::size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

void run(const Options& o, const tool::CommonOptions& common) {
    rt::RenderScene rs;
    if (!o.pool.empty() || !o.scene.empty()) {
        rs = o.scene.empty() ? rt::RenderScene::from_pool(o.pool)
                             : rt::RenderScene::load(scene::load_scene(o.scene), o.pool);
    } else {
        scene::Scene sc;
        sc.materials.push_back(scene::Material{});
        sc.materials.back().name = "walls";
        sc.camera.position = {0, 0, 0.9};
        sc.camera.look_at = {0, -0.1, -1};
        sc.camera.fov_y_degrees = 60;
        scene::PointLight light;
        light.position = {0.2, 0.8, 0.3};
        sc.point_lights.push_back(light);
        rs = rt::RenderScene::from_pools(
            sc, {synthetic_pool(o.synthetic, o.max_leaf, o.save_pool, common.quiet)});
    }
    rs.scene().camera.width = o.width;
    rs.scene().camera.height = o.height;
    if (rs.lights().empty()) {
        scene::PointLight light;
        const auto lo = rs.world_min(), hi = rs.world_max();
        light.position = {hi[0], hi[1] + (hi[1] - lo[1]), hi[2]};
        rs.scene().point_lights.push_back(light);
        rs.update_lights();
    }
    core::RenderParams base = rs.params();
    player::apply(o.render, base);

    auto backend = rt::make_backend(o.backend.name, player::backend_options(o.backend));
    const double t0 = tool::now_seconds();
    const rt::UploadStats up = backend->set_scene(rs.view());
    const double load_s = tool::now_seconds() - t0;

    std::vector<Scenario> all;
    {
        Scenario s{"primary", "primary rays, local shading, 1 light without shadows", base, false, 1.0};
        s.params.shadows = 0;
        s.params.max_bounces = 0;
        all.push_back(s);
        Scenario t{"shadow", "primary + 1 shadow ray per lit hit", base, false, 0.8};
        t.params.shadows = 1;
        t.params.max_bounces = 0;
        all.push_back(t);
        Scenario r{"reflect4", "primary + 4 bounces of reflection (reflectivity 0.8), no shadows", base, true,
                   0.5};
        r.params.shadows = 0;
        r.params.reflections = 1;
        r.params.max_bounces = 4;
        r.params.min_ray_weight = 0.0f;  // every bounce is traced
        all.push_back(r);
    }
    const std::vector<core::Material> original(rs.view().materials,
                                               rs.view().materials + rs.view().material_count);

    nlohmann::json report;
    report["device"] = backend->device();
    report["backend"] = backend->name();
    report["kernel"] = o.backend.kernel;
    report["mapping"] = o.backend.mapping;
    report["width"] = o.width;
    report["height"] = o.height;
    report["frames"] = o.frames;
    report["warmup"] = o.warmup;
    std::uint64_t splats = 0, points = 0;
    for (const auto& m : rs.models()) {
        splats += m.view.octree.splat_count;
        points += m.view.point_count;
    }
    report["model"] = {{"points", points}, {"splats", splats}, {"bytes", rs.bytes()}};
    report["load"] = {{"seconds", load_s},
                      {"upload_bytes", up.bytes},
                      {"upload_seconds", up.seconds},
                      {"upload_gb_per_s", up.gb_per_s()}};
    std::printf(
        "prt-bench: %s on %s, %ux%u, %llu points (%llu splats), median of %u frames after %u warm-up\n",
        backend->name().c_str(), backend->device().c_str(), o.width, o.height,
        static_cast<unsigned long long>(points), static_cast<unsigned long long>(splats), o.frames, o.warmup);
    std::printf("%-10s %10s %8s %12s %12s %12s %12s %10s %8s\n", "scenario", "ms/frame", "fps", "rays/frame",
                "primary", "shadow", "secondary", "Grays/s", "target");
    for (const Scenario& sc : all) {
        if (o.scenarios.find(sc.name) == std::string::npos) continue;
        // Materials of the scenario (the mirror world of reflect4), uploaded before timing.
        std::vector<core::Material> mats = original;
        if (sc.mirror) {
            for (core::Material& m : mats) {
                m.reflectivity = 0.8f;
                m.diffuse_reflectance = 0.2f;
                m.transmissivity = 0.0f;
            }
        }
        core::SceneView view = rs.view();
        view.materials = mats.data();
        backend->set_scene(view);
        rt::FrameRequest req;
        req.camera = rs.camera();
        req.params = sc.params;
        req.width = o.width;
        req.height = o.height;
        req.download = false;
        rt::Image image;
        image.resize(o.width, o.height);
        for (std::uint32_t i = 0; i < o.warmup; ++i) backend->render(req, image);
        std::vector<double> ms;
        rt::FrameStats last;
        tool::Progress progress("prt-bench: " + sc.name, o.frames, common.quiet);
        for (std::uint32_t i = 0; i < o.frames; ++i) {
            last = backend->render(req, image);
            // CUDA: kernel time from events; CPU and hybrid: the frame's wall time.
            ms.push_back(backend->name() == "cuda" ? last.device_ms : last.seconds * 1e3);
            progress.update(i + 1);
        }
        progress.finish();
        const double med = median(ms);
        const double grays = med > 0 ? last.rays() / (med * 1e-3) * 1e-9 : 0;
        std::printf("%-10s %10.3f %8.1f %12llu %12llu %12llu %12llu %10.3f %8.2f\n", sc.name.c_str(), med,
                    1e3 / med, static_cast<unsigned long long>(last.rays()),
                    static_cast<unsigned long long>(last.primary),
                    static_cast<unsigned long long>(last.shadow),
                    static_cast<unsigned long long>(last.secondary), grays, sc.target_grays);
        report["scenarios"].push_back(
            {{"name", sc.name},
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
             {"leaves_per_ray", last.rays() ? double(last.leaves) / last.rays() : 0.0},
             {"splat_tests_per_ray", last.rays() ? double(last.splat_tests) / last.rays() : 0.0},
             {"truncated", last.truncated},
             {"sanitized", last.sanitized},
             {"timer", backend->name() == "cuda" ? "cuda events" : "host clock"},
             {"gpu_share", last.gpu_share},
             {"target_grays_per_s", sc.target_grays},
             {"meets_target", grays >= sc.target_grays}});
    }
    if (!o.json.empty()) {
        std::ofstream f(o.json);
        if (!f) throw Error(o.json + ": cannot write");
        f << report.dump(2) << "\n";
        if (!f) throw Error(o.json + ": write failed");
    }
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    return prt::tool::run(
        argc, argv, "prt-bench",
        "PointRT benchmark: rays per second by ray kind and frames per second for three scenarios (primary; "
        "one "
        "shadow light; 4-bounce reflections), median over frames after warm-up (CUDA events on the GPU). "
        "Without a "
        "pool or scene it renders a synthetic room of --synthetic points from inside.",
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("pool", o.pool, "Pool with the octree sections (default: the synthetic room)")
                ->check(CLI::ExistingFile);
            app.add_option("--scene", o.scene, "Scene JSON (camera, lights, materials)")
                ->check(CLI::ExistingFile);
            app.add_option("--synthetic", o.synthetic, "Points of the synthetic room when no pool is given")
                ->check(CLI::Range(std::uint64_t{1000}, std::uint64_t{1} << 31));
            app.add_option("--max-leaf", o.max_leaf,
                           "Synthetic room: splats per octree leaf before a split (thesis 3.2's X)")
                ->check(CLI::Range(1u, 100000u));
            app.add_option("--save-pool", o.save_pool, "Also write the synthetic room's pool here");
            app.add_option("--width", o.width, "Image width")->check(CLI::Range(1u, 16384u));
            app.add_option("--height", o.height, "Image height")->check(CLI::Range(1u, 16384u));
            app.add_option("--frames", o.frames, "Timed frames per scenario (the median is reported)")
                ->check(CLI::Range(1u, 100000u));
            app.add_option("--warmup", o.warmup, "Untimed frames before timing")
                ->check(CLI::Range(0u, 100000u));
            app.add_option("--scenarios", o.scenarios, "Comma-separated subset of primary,shadow,reflect4");
            app.add_option("--json", o.json, "Write the results as JSON to this file");
            prt::player::add_backend_options(app, o.backend);
            prt::player::add_render_options(app, o.render);
        },
        [&](const prt::tool::CommonOptions& common) { run(o, common); });
}
