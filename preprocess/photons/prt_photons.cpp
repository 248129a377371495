// prt-photons: caustics (thesis 5.4): shoots photons from every point light of a scene (cube faces
// of pixels, jittered photons per pixel) and every area light (uniform over its area, cosine-weighted
// about its normal; issue 20), keeps the L S+ D paths, and writes a caustic octree
// (density estimates at leaf corners, eq. 5.1-5.2) into each model's pool, in place.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "gi_frame.h"
#include "photons.h"
#include "prt/formats/gi_sections.h"
#include "prt/formats/scene.h"
#include "prt/pool_step.h"
#include "prt/runtime/render_scene.h"
#include "prt/scene_pools.h"

namespace {

constexpr const char* k_description =
    "Caustics (thesis 5.4). Loads SCENE.json and its pools, covers every point light with a cube whose 6 "
    "faces are --face-res x --face-res pixels, shoots --per-pixel photons per pixel with jittered "
    "directions, each carrying the power of its pixel's solid angle (a light of color I emits 4 pi I); "
    "every area light shoots as many photons, from points uniform over its area (--face-res x --face-res "
    "cells) in directions cosine-distributed about its normal edge_u x edge_v (a Lambertian emitter of "
    "power pi I: along its normal as bright as a point light of color I). Photons are traced with the "
    "renderer's core (on the GPU when there is one). "
    "Only L "
    "S+ D paths are kept: photons whose first hit is not specular, or that leave the scene, are dropped; "
    "specular hits reflect or refract (power x reflectivity + transmissivity) up to --max-bounces; after "
    "a "
    "specular hit, a surface with a diffuse share receives a deposit. Deposits go into each model's "
    "caustic "
    "octree (model local frame, --caustic-levels below the reference level: the splat octree's or bricks' "
    "depth, "
    "else the level where the model's points (ISO, MLS) or points sampled on its patches fill cells 8 to a "
    "cell on average) with a density estimate "
    "at "
    "every leaf corner (eq. 5.1-5.2, radius --gather-radius leaf edges); the renderer interpolates them. "
    "Each pool is rewritten in place, atomically, with its other sections carried over; pools that got "
    "no "
    "deposit lose any old caustic sections.";

using ull = unsigned long long;

/// The options of prt-photons.
struct Options {
    prt::photons::ShootOptions shoot;
    std::uint32_t caustic_levels = 2;
    float radius = 1.0f, cos_threshold = 0.0f;
};

/// One caustic map: the placement it belongs to (pool::placement_key, 0: any), the model's scale
/// there, the deposits and the octree built.
struct MapJob {
    std::uint32_t placement = 0;
    float scale = 1;
    std::vector<prt::photons::PhotonDeposit> deposits;
    std::optional<prt::gi::GiOctree> tree;
};

/// One pool's caustic maps (issue 20: one per placement; a pool placed once gets one map for any
/// placement, key 0, as before) and its splat octree's root, their common frame.
struct PoolJob {
    double root_min[3];
    double root_size = 1;
    std::uint32_t depth = 0;
    std::string frame_from;  ///< what the frame came from (gi::GiFrame::from)
    std::vector<MapJob> maps;
};

using Pools = prt::tool::ScenePools;

/// The scene's pools: a pool placed more than once gets a map per placement (local frame each).
Pools scene_pools(const prt::tool::PoolStep& step, const prt::scene::Scene& sc) {
    return prt::tool::scene_pools(sc, [&](const std::filesystem::path& p) {
        step.note("prt-photons: %s: pool %s placed more than once: one caustic map per placement",
                  step.input_path().c_str(), p.string().c_str());
    });
}

/// Per model: the index of its map in its pool's job (models placing a pool at the same transform
/// share one).
std::vector<std::uint32_t> assign_maps(const prt::scene::Scene& sc, const Pools& pools,
                                       std::vector<PoolJob>& jobs) {
    std::vector<std::uint32_t> map_of_model(sc.models.size(), 0);
    for (std::size_t m = 0; m < sc.models.size(); ++m) {
        const std::uint32_t p = pools.of_model[m];
        const std::uint32_t key = pools.map_key[m];
        std::vector<MapJob>& maps = jobs[p].maps;
        std::size_t k = 0;
        while (k < maps.size() && maps[k].placement != key) ++k;
        if (k == maps.size()) {
            maps.push_back(MapJob{});
            maps[k].placement = key;
            maps[k].scale = static_cast<float>(sc.models[m].transform.scale);
        }
        map_of_model[m] = static_cast<std::uint32_t>(k);
    }
    return map_of_model;
}

/// Shoots the photons; the RenderScene maps the pools rewritten later: it lives only in here.
prt::photons::ShootResult shoot(const prt::tool::PoolStep& step, const prt::scene::Scene& sc,
                                const Options& o, const Pools& pools, std::vector<PoolJob>& jobs,
                                std::uint64_t& lights, double& load_seconds, std::future<void>& device) {
    using namespace prt;
    const rt::RenderScene rs = rt::RenderScene::load(sc);
    for (const std::string& w : rs.warnings()) step.note("prt-photons: %s", w.c_str());
    for (std::size_t m = 0; m < rs.models().size(); ++m) {
        // Issue 20: the caustic map's frame on whatever surface the model is traced as (gi_frame.h).
        PoolJob& job = jobs[pools.of_model[m]];
        const pool::PoolFile& pf = *rs.models()[m].pool;
        gi::GiFrame frame;
        try {
            if (gi::frame_needs_points(pf)) {
                const gi::SurfacePoints points = gi::surface_points(pf);
                frame = gi::gi_frame(pf, &points);
            } else {
                frame = gi::gi_frame(pf, nullptr);
            }
        } catch (const Error& e) {
            throw Error(step.input_path() + ": model '" + sc.models[m].name + "': " + e.what());
        }
        for (int a = 0; a < 3; ++a) job.root_min[a] = frame.root_min[a];
        job.root_size = frame.root_size;
        job.depth = frame.depth;
        job.frame_from = frame.from;
    }
    const core::SceneView view = rs.view();
    lights = core::photon_light_count(view);
    load_seconds = step.seconds();
    const std::uint64_t total = photons::photons_per_light(o.shoot.params) * lights;
    step.note("prt-photons: %u point + %u area lights x %llu photons (%u x %u x 6 faces x %u), backend %s",
              view.point_light_count, view.area_light_count, ull(photons::photons_per_light(o.shoot.params)),
              o.shoot.params.face_res, o.shoot.params.face_res, o.shoot.params.per_pixel,
              o.shoot.backend.c_str());
    device.wait();  // the GPU's context, created while the scene loaded
    tool::Progress progress("prt-photons: shooting", total, step.quiet());
    photons::ShootResult shot =
        photons::shoot_photons(view, o.shoot, [&](std::uint64_t d, std::uint64_t) { progress.update(d); });
    progress.finish();
    return shot;
}

/// Builds one map's caustic octree (eq. 5.1-5.2) in its pool's frame; returns its leaves, adds the
/// phase times.
std::uint64_t gather_map(const prt::tool::PoolStep& step, const Options& o, const std::filesystem::path& path,
                         PoolJob& job, std::size_t index, const prt::photons::PhotonTally& t,
                         double gather_phases[5]) {
    MapJob& map = job.maps[index];
    using namespace prt;
    photons::GatherOptions g;
    g.depth = std::min(job.depth + o.caustic_levels, pool::k_max_gi_depth);
    g.radius_edges = o.radius;
    g.render_scale = map.scale;
    g.cos_threshold = o.cos_threshold;
    g.threads = o.shoot.threads;
    double phases[5] = {0, 0, 0, 0, 0};
    g.phase_seconds = phases;
    map.tree = photons::build_caustic_octree(map.deposits, job.root_min, job.root_size, g);
    for (int k = 0; k < 5; ++k) gather_phases[k] += phases[k];
    map.tree->info.placement = map.placement;
    map.tree->info.total[0] = 0.0f;
    for (const photons::PhotonDeposit& d : map.deposits)
        map.tree->info.total[0] += 0.2126f * d.flux[0] + 0.7152f * d.flux[1] + 0.0722f * d.flux[2];
    map.tree->info.total[1] =
        static_cast<float>(0.2126 * t.emitted[0] + 0.7152 * t.emitted[1] + 0.0722 * t.emitted[2]);
    const std::string which = job.maps.size() > 1 ? " placement " + std::to_string(index + 1) + " of " +
                                                        std::to_string(job.maps.size())
                                                  : std::string();
    step.note("prt-photons: %s%s: %zu deposits, caustic octree depth %u (frame of %s), %zu leaves (%.1f MiB)",
              path.filename().string().c_str(), which.c_str(), map.deposits.size(), g.depth,
              job.frame_from.c_str(), map.tree->leaves.size(),
              double(map.tree->leaves.size() * sizeof(pool::GiLeaf) + map.tree->nodes.size() * 4) /
                  (1024.0 * 1024.0));
    return map.tree->leaves.size();
}

/// Builds each pool's caustic octree (eq. 5.1-5.2); returns the leaves, sums the phase times.
std::uint64_t gather(const prt::tool::PoolStep& step, const Options& o, const Pools& pools,
                     const prt::photons::PhotonTally& t, std::vector<PoolJob>& jobs,
                     double gather_phases[5]) {
    using namespace prt;
    std::uint64_t leaves = 0;
    for (std::size_t p = 0; p < jobs.size(); ++p) {
        for (std::size_t k = 0; k < jobs[p].maps.size(); ++k)
            if (!jobs[p].maps[k].deposits.empty())
                leaves += gather_map(step, o, pools.paths[p], jobs[p], k, t, gather_phases);
    }
    return leaves;
}

void report(const prt::tool::PoolStep& step, const prt::photons::ShootResult& shot) {
    const prt::photons::PhotonTally& t = shot.tally;
    auto lum = [](const double c[3]) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; };
    const double emitted = lum(t.emitted);
    auto pct = [&](const double c[3]) { return emitted > 0 ? 100.0 * lum(c) / emitted : 0.0; };
    step.note(
        "prt-photons: %llu photons in %.3f s (%.1f M photons/s; tracing alone %.3f s, %.1f M/s; device setup "
        "and "
        "scene upload %.3f s; %s); %llu deposits, %llu specular hits",
        ull(t.photons), shot.seconds, shot.seconds > 0 ? double(t.photons) / shot.seconds * 1e-6 : 0.0,
        shot.kernel_seconds, shot.kernel_seconds > 0 ? double(t.photons) / shot.kernel_seconds * 1e-6 : 0.0,
        shot.setup_seconds, shot.backend.c_str(), ull(t.deposits), ull(t.specular_hits));
    step.note(
        "prt-photons: power: direct %.2f %%, deposited (x albedo share) %.2f %%, absorbed %.2f %%, escaped "
        "%.2f %%, cut at the bounce limit %.4f %%",
        pct(t.direct), pct(t.deposited), pct(t.absorbed), pct(t.escaped), pct(t.truncated));
}

nlohmann::json tally_json(const prt::photons::ShootResult& shot) {
    const prt::photons::PhotonTally& t = shot.tally;
    auto rgb = [](const double c[3]) { return nlohmann::json::array({c[0], c[1], c[2]}); };
    return {{"backend", shot.backend},
            {"photons", t.photons},
            {"deposits", t.deposits},
            {"specular_hits", t.specular_hits},
            {"rays", t.rays},
            {"emitted", rgb(t.emitted)},
            {"direct", rgb(t.direct)},
            {"deposited", rgb(t.deposited)},
            {"absorbed", rgb(t.absorbed)},
            {"escaped", rgb(t.escaped)},
            {"truncated", rgb(t.truncated)},
            {"shoot_seconds", shot.seconds},
            {"trace_seconds", shot.kernel_seconds},
            {"photons_per_second", shot.seconds > 0 ? double(t.photons) / shot.seconds : 0.0}};
}

void photons_step(prt::tool::PoolStep& step, Options o) {
    using namespace prt;
    double load_seconds = 0;  // scene, pools and the render scene
    const scene::Scene sc = scene::load_scene(step.input_path());
    if (sc.models.empty()) throw Error(step.input_path() + ": no models");
    std::string why;
    o.shoot.backend = photons::resolve_backend(o.shoot.backend, &why);
    if (!why.empty()) step.note("prt-photons: --backend auto: using the CPU (%s)", why.c_str());
    std::future<void> device = photons::warm_up(o.shoot.backend);

    const Pools pools = scene_pools(step, sc);
    std::vector<PoolJob> jobs(pools.paths.size());
    const std::vector<std::uint32_t> map_of_model = assign_maps(sc, pools, jobs);
    std::uint64_t lights = 0;
    photons::ShootResult shot = shoot(step, sc, o, pools, jobs, lights, load_seconds, device);
    for (const photons::PhotonDeposit& d : shot.deposits)
        jobs[pools.of_model[d.model]].maps[map_of_model[d.model]].deposits.push_back(d);
    std::vector<photons::PhotonDeposit>().swap(shot.deposits);

    const double gather_start = tool::now_seconds();
    double gather_phases[5] = {0, 0, 0, 0, 0};  // summed over the pools
    const std::uint64_t leaves = gather(step, o, pools, shot.tally, jobs, gather_phases);
    const double gather_seconds = tool::now_seconds() - gather_start;

    nlohmann::json parameters = {{"face_res", o.shoot.params.face_res},
                                 {"per_pixel", o.shoot.params.per_pixel},
                                 {"max_bounces", o.shoot.params.max_bounces},
                                 {"caustic_levels", o.caustic_levels},
                                 {"gather_radius", o.radius},
                                 {"cos_threshold", o.cos_threshold},
                                 {"seed", o.shoot.params.seed},
                                 {"scene", step.input_path()}};
    // --provenance-tag (scripts/prt-bake, prt-batch): recorded in each pool's entry as PoolStep::write does.
    if (!step.provenance_tag().empty()) parameters["tag"] = nlohmann::json::parse(step.provenance_tag());
    const double write_start = tool::now_seconds();
    for (std::size_t p = 0; p < jobs.size(); ++p) {
        std::vector<const gi::GiOctree*> trees;
        for (const MapJob& map : jobs[p].maps)
            if (map.tree) trees.push_back(&*map.tree);
        gi::write_gi_pool(pools.paths[p], gi::k_caustic_sections, trees, "prt-photons", parameters.dump());
    }
    const double write_seconds = tool::now_seconds() - write_start;

    report(step, shot);
    const double total_seconds = step.seconds();
    step.note(
        "prt-photons: gather %.3f s (%llu leaves: bin %.3f s, blocks %.3f s, densities + leaves %.3f s, "
        "encode %.3f s, octree %.3f s)",
        gather_seconds, ull(leaves), gather_phases[0], gather_phases[1], gather_phases[2], gather_phases[3],
        gather_phases[4]);
    step.note(
        "prt-photons: phases: load %.3f s, trace %.3f s, gather %.3f s, pool writes %.3f s; total %.3f s",
        load_seconds, shot.seconds, gather_seconds, write_seconds, total_seconds);
    nlohmann::json j = tally_json(shot);
    j["scene"] = step.input_path();
    j["parameters"] = parameters;
    j["lights"] = lights;
    j["gather_seconds"] = gather_seconds;
    j["gather_phase_seconds"] = {{"bin", gather_phases[0]},
                                 {"blocks", gather_phases[1]},
                                 {"densities_leaves", gather_phases[2]},
                                 {"encode", gather_phases[3]},
                                 {"octree", gather_phases[4]}};
    j["load_seconds"] = load_seconds;
    j["write_seconds"] = write_seconds;
    j["total_seconds"] = total_seconds;
    j["leaves"] = leaves;
    step.write_stats(std::move(j));
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    prt::tool::PoolStep step(
        "prt-photons", k_description,
        prt::tool::PoolStep::scene_help("Also write the statistics (power accounting) as JSON here"));
    return step.run(
        argc, argv,
        [&](CLI::App& app) {
            app.add_option("--face-res", o.shoot.params.face_res, "Pixels per side of each cube face")
                ->check(CLI::Range(1u, 8192u));
            app.add_option("--per-pixel", o.shoot.params.per_pixel, "Photons per pixel, jittered inside it")
                ->check(CLI::Range(1u, 1024u));
            app.add_option("--max-bounces", o.shoot.params.max_bounces, "Specular bounces a photon may make")
                ->check(CLI::Range(1u, 64u));
            app.add_option("--caustic-levels", o.caustic_levels,
                           "Levels of the caustic octree below the model's reference level (the splat "
                           "octree's depth, "
                           "or one from its points or patches; leaf level capped at 20)")
                ->check(CLI::Range(0u, 12u));
            app.add_option("--gather-radius", o.radius,
                           "Gather radius g of eq. 5.1-5.2, in caustic leaf edges")
                ->check(CLI::Range(0.25f, 4.0f));
            app.add_option(
                   "--cos-threshold", o.cos_threshold,
                   "Lookups whose normal makes a cosine below this with a leaf's deposit normal see no "
                   "caustic there (0: the other side of a surface sees none)")
                ->check(CLI::Range(-1.0f, 1.0f));
            app.add_option("--seed", o.shoot.params.seed,
                           "Seed of the jitter and of the reflect/refract choices");
            app.add_option("--backend", o.shoot.backend,
                           "auto (CUDA when a device is usable, else CPU), cpu or cuda")
                ->check(CLI::IsMember({"auto", "cpu", "cuda"}));
            prt::tool::PoolStep::add_threads(app, o.shoot.threads,
                                             "CPU worker threads (0 = every core the process may use)");
        },
        [&](prt::tool::PoolStep& s) { photons_step(s, o); });
}
