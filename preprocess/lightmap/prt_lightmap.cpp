// prt-lightmap: a diffuse light map (thesis 5.3) per model of a scene: indirect illumination and
// color bleeding path traced from surface samples, gathered at the corners of a light-map octree
// (eq. 5.3-5.4, normal rejection) and written into each model's pool, in place.
#include <algorithm>
#include <filesystem>
#include <future>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lightmap.h"
#include "photons.h"
#include "prt/formats/scene.h"
#include "prt/pool_step.h"
#include "prt/runtime/render_scene.h"
#include "prt/scene_pools.h"

namespace {

constexpr const char* k_description =
    "Diffuse light map (thesis 5.3), on the CPU or the GPU (--backend). Loads SCENE.json and its pools, "
    "picks up to --samples-per-leaf of "
    "each "
    "model's points (or of points sampled on its patches) in every cell of the light-map level "
    "(--levels-above levels above the model's reference level: its splat octree's or bricks' depth, else "
    "the level where its points fill cells 8 to a cell on average), moves each onto the surface the model "
    "is traced as (ISO, MLS, patches: a probe ray along its normal), and path traces each one's indirect "
    "irradiance with the renderer's core: --rays "
    "cosine-distributed paths of up to --bounces vertices, each vertex adding the direct light there "
    "(Lambert, shadow rays) and continuing diffusely, specularly or by refraction in proportion to its "
    "material. The samples are gathered at the corners of a light-map octree with the weighted average "
    "of eq. "
    "5.3-5.4 (weight (1 - d/g)^2, radius --gather-radius leaf edges), rejecting samples whose normal "
    "makes a "
    "cosine below --normal-reject with the leaf's. The renderer replaces its constant ambient term with "
    "the "
    "interpolated irradiance x albedo. Each pool is rewritten in place, atomically, other sections "
    "carried "
    "over.";

/// The options of prt-lightmap.
struct Options {
    prt::lightmap::TraceParams trace;
    prt::lightmap::GatherOptions gather;
    std::uint32_t levels_above = 1, per_leaf = 4;
    unsigned threads = 0;
    std::string backend = "auto";  ///< auto | cpu | cuda (issue 20: the light map on the GPU)
};

using Pools = prt::tool::ScenePools;

/// The scene's pools: a pool placed more than once gets a map per placement (issue 20).
Pools scene_pools(const prt::tool::PoolStep& step, const prt::scene::Scene& sc) {
    return prt::tool::scene_pools(sc, [&](const std::filesystem::path& p) {
        step.note("prt-lightmap: pool %s placed more than once: one light map per placement",
                  p.string().c_str());
    });
}

/// Traces the samples of each placement of each pool and builds its light-map octree (thesis 5.3):
/// per pool, one map keyed 0 (any placement) when the scene places it once, else one map per
/// distinct placement keyed pool::placement_key (issue 20: the indirect light depends on where the
/// model stands). The RenderScene maps the pools rewritten later: it lives only in here.
std::vector<std::vector<prt::gi::GiOctree>> build_maps(const prt::tool::PoolStep& step,
                                                       const prt::scene::Scene& sc, Options& o,
                                                       const Pools& pools, std::uint64_t& total_samples,
                                                       double& trace_seconds, std::string& backend,
                                                       double& kernel_seconds) {
    using namespace prt;
    std::vector<std::vector<gi::GiOctree>> trees(pools.paths.size());
    // The GPU's context is created on a thread while the scene loads (photons::warm_up).
    std::string why;
    o.backend = photons::resolve_backend(o.backend, &why);
    if (!why.empty()) step.note("prt-lightmap: --backend auto: using the CPU (%s)", why.c_str());
    std::future<void> device = photons::warm_up(o.backend);
    const rt::RenderScene rs = rt::RenderScene::load(sc);
    for (const std::string& w : rs.warnings()) step.note("prt-lightmap: %s", w.c_str());
    const core::SceneView view = rs.view();
    for (std::size_t m = 0; m < rs.models().size(); ++m) {
        const std::uint32_t p = pools.of_model[m];
        const std::uint32_t key = pools.map_key[m];
        if (std::any_of(trees[p].begin(), trees[p].end(),
                        [&](const gi::GiOctree& t) { return t.info.placement == key; }))
            continue;  // placed twice at the same spot: one map serves both
        const pool::PoolFile& pf = *rs.models()[m].pool;
        // Issue 20: samples and frame on whatever surface the model is traced as (gi_frame.h).
        gi::SurfacePoints points;
        gi::GiFrame frame;
        try {
            points = gi::surface_points(pf);
            frame = gi::gi_frame(pf, &points);
        } catch (const Error& e) {
            throw Error(step.input_path() + ": model '" + sc.models[m].name + "': " + e.what());
        }
        const double* root_min = frame.root_min;
        const double root_size = frame.root_size;
        o.gather.depth = frame.depth > o.levels_above ? frame.depth - o.levels_above : 0;
        const float reach = lightmap::settle_reach(view.models[m].surface, points,
                                                   root_size / static_cast<double>(1ull << o.gather.depth));
        std::vector<lightmap::Sample> samples =
            lightmap::select_samples(points, static_cast<std::uint32_t>(m), view.models[m], root_min,
                                     root_size, o.gather.depth, o.per_leaf, reach);
        device.wait();
        const double t0 = tool::now_seconds();
        {
            tool::Progress progress("prt-lightmap: " + pools.paths[p].filename().string(), samples.size(),
                                    step.quiet());
            const lightmap::TraceReport r = lightmap::trace_samples(
                view, o.trace, samples, total_samples, o.threads,
                [&](std::uint64_t d) { progress.update(d); }, o.backend);
            progress.finish();
            backend = r.backend;
            kernel_seconds += r.kernel_seconds;
        }
        trace_seconds += tool::now_seconds() - t0;
        total_samples += samples.size();
        const std::size_t dropped = lightmap::drop_unsettled(samples);
        if (samples.empty())
            throw Error(step.input_path() + ": model '" + sc.models[m].name + "': none of its " +
                        std::to_string(dropped) + " light-map samples lies on its traced surface");
        gi::GiOctree& tree =
            trees[p].emplace_back(lightmap::build_light_map_octree(samples, root_min, root_size, o.gather));
        tree.info.placement = key;
        const std::string which =
            key != 0 ? " (model '" + sc.models[m].name + "''s placement)" : std::string();
        step.note(
            "prt-lightmap: %s%s: %zu samples on %s (frame of %s, %s surface%s), level %u, %zu leaves, "
            "mean irradiance %.4g, max %.4g",
            pools.paths[p].filename().string().c_str(), which.c_str(), samples.size(), points.from.c_str(),
            frame.from.c_str(), std::string(scene::surface_name(sc.models[m].surface)).c_str(),
            dropped ? (", " + std::to_string(dropped) + " off the surface dropped").c_str() : "",
            o.gather.depth, tree.leaves.size(), tree.info.total[0], tree.info.total[1]);
    }
    return trees;
}

void lightmap_step(prt::tool::PoolStep& step, Options o) {
    using namespace prt;
    const scene::Scene sc = scene::load_scene(step.input_path());
    if (sc.models.empty()) throw Error(step.input_path() + ": no models");
    const Pools pools = scene_pools(step, sc);
    std::uint64_t total_samples = 0;
    double trace_seconds = 0, kernel_seconds = 0;
    std::string backend;
    o.gather.threads = o.threads;
    const std::vector<std::vector<gi::GiOctree>> trees =
        build_maps(step, sc, o, pools, total_samples, trace_seconds, backend, kernel_seconds);
    nlohmann::json parameters = {{"rays", o.trace.rays},
                                 {"bounces", o.trace.bounces},
                                 {"levels_above", o.levels_above},
                                 {"samples_per_leaf", o.per_leaf},
                                 {"gather_radius", o.gather.radius_edges},
                                 {"normal_reject", o.gather.reject_cos},
                                 {"seed", o.trace.seed},
                                 {"scene", step.input_path()}};
    // --provenance-tag (scripts/prt-bake, prt-batch): recorded in each pool's entry as PoolStep::write does.
    if (!step.provenance_tag().empty()) parameters["tag"] = nlohmann::json::parse(step.provenance_tag());
    for (std::size_t p = 0; p < pools.paths.size(); ++p) {
        std::vector<const gi::GiOctree*> maps;
        for (const gi::GiOctree& t : trees[p])
            if (!t.leaves.empty()) maps.push_back(&t);
        gi::write_gi_pool(pools.paths[p], gi::k_light_map_sections, maps, "prt-lightmap", parameters.dump());
    }
    step.note(
        "prt-lightmap: %llu samples x %u paths traced on %s in %.3f s (tracing %.3f s; upload and download "
        "included in the first); total %.3f s",
        static_cast<unsigned long long>(total_samples), o.trace.rays, backend.c_str(), trace_seconds,
        kernel_seconds, step.seconds());
    nlohmann::json per_pool = nlohmann::json::array();
    for (std::size_t p = 0; p < pools.paths.size(); ++p) {
        nlohmann::json maps = nlohmann::json::array();
        std::size_t leaves = 0;
        for (const gi::GiOctree& t : trees[p]) {
            maps.push_back({{"placement", t.info.placement},
                            {"leaves", t.leaves.size()},
                            {"mean", t.info.total[0]},
                            {"max", t.info.total[1]}});
            leaves += t.leaves.size();
        }
        // "mean" and "max": the first map's (the only one for a pool placed once).
        per_pool.push_back({{"pool", pools.paths[p].string()},
                            {"leaves", leaves},
                            {"mean", trees[p].empty() ? 0.0f : trees[p][0].info.total[0]},
                            {"max", trees[p].empty() ? 0.0f : trees[p][0].info.total[1]},
                            {"maps", maps}});
    }
    step.write_stats({{"scene", step.input_path()},
                      {"parameters", parameters},
                      {"samples", total_samples},
                      {"trace_seconds", trace_seconds},
                      {"kernel_seconds", kernel_seconds},
                      {"backend", backend},
                      {"pools", per_pool}});
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    prt::tool::PoolStep step("prt-lightmap", k_description,
                             prt::tool::PoolStep::scene_help("Also write the statistics as JSON here"));
    return step.run(
        argc, argv,
        [&](CLI::App& app) {
            app.add_option("--rays", o.trace.rays, "Paths per sample")->check(CLI::Range(1u, 65536u));
            app.add_option("--bounces", o.trace.bounces,
                           "Vertices per path (1 = one diffuse bounce of direct light)")
                ->check(CLI::Range(1u, 16u));
            app.add_option("--levels-above", o.levels_above,
                           "Light-map leaf level: this many levels above the model's reference level "
                           "(its splat octree's depth, or one from its points or patches)")
                ->check(CLI::Range(0u, 12u));
            app.add_option("--samples-per-leaf", o.per_leaf, "Points traced per light-map cell at most")
                ->check(CLI::Range(1u, 64u));
            app.add_option("--gather-radius", o.gather.radius_edges,
                           "Gather radius g of eq. 5.3, in light-map leaf edges")
                ->check(CLI::Range(0.5f, 4.0f));
            app.add_option(
                   "--normal-reject", o.gather.reject_cos,
                   "Samples whose normal makes a cosine below this with the leaf's normal are not gathered")
                ->check(CLI::Range(-1.0f, 1.0f));
            app.add_option("--seed", o.trace.seed, "Seed of the path directions");
            app.add_option(
                   "--backend", o.backend,
                   "Where the samples are traced: auto (the GPU when there is one), cpu or cuda; both run "
                   "the same core function")
                ->check(CLI::IsMember({"auto", "cpu", "cuda"}));
            prt::tool::PoolStep::add_threads(app, o.threads, "CPU worker threads (0 = every core the process may use)");
        },
        [&](prt::tool::PoolStep& s) { lightmap_step(s, o); });
}
