// prt-lightmap: a diffuse light map (thesis 5.3) per model of a scene: indirect illumination and
// color bleeding path traced from surface samples, gathered at the corners of a light-map octree
// (eq. 5.3-5.4, normal rejection) and written into each model's pool, in place.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "lightmap.h"
#include "prt/formats/pool.h"
#include "prt/formats/scene.h"
#include "prt/runtime/render_scene.h"
#include "prt/tool.h"

int main(int argc, char** argv) {
    std::string scene_path, stats_json;
    prt::lightmap::TraceParams trace;
    prt::lightmap::GatherOptions gather;
    std::uint32_t levels_above = 1, per_leaf = 4;
    unsigned threads = 0;
    return prt::tool::run(
        argc, argv, "prt-lightmap",
        "Diffuse light map (thesis 5.3). Loads SCENE.json and its pools, picks up to --samples-per-leaf of "
        "each "
        "model's points in every cell of the light-map level (--levels-above levels above the splat octree's "
        "depth), and path traces each one's indirect irradiance with the renderer's core: --rays "
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
        "over.",
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("scene", scene_path,
                           "Scene file (formats/SCENE.md); its models need pools with an octree")
                ->required();
            app.add_option("--rays", trace.rays, "Paths per sample")
                ->check(CLI::Range(1u, 65536u))
                ->capture_default_str();
            app.add_option("--bounces", trace.bounces,
                           "Vertices per path (1 = one diffuse bounce of direct light)")
                ->check(CLI::Range(1u, 16u))
                ->capture_default_str();
            app.add_option("--levels-above", levels_above,
                           "Light-map leaf level: this many levels above the splat octree's depth")
                ->check(CLI::Range(0u, 12u))
                ->capture_default_str();
            app.add_option("--samples-per-leaf", per_leaf, "Points traced per light-map cell at most")
                ->check(CLI::Range(1u, 64u))
                ->capture_default_str();
            app.add_option("--gather-radius", gather.radius_edges,
                           "Gather radius g of eq. 5.3, in light-map leaf edges")
                ->check(CLI::Range(0.5f, 4.0f))
                ->capture_default_str();
            app.add_option(
                   "--normal-reject", gather.reject_cos,
                   "Samples whose normal makes a cosine below this with the leaf's normal are not gathered")
                ->check(CLI::Range(-1.0f, 1.0f))
                ->capture_default_str();
            app.add_option("--seed", trace.seed, "Seed of the path directions")->capture_default_str();
            app.add_option("-j,--threads", threads, "CPU worker threads (0 = all hardware threads)")
                ->capture_default_str();
            app.add_option("--stats-json", stats_json, "Also write the statistics as JSON here");
        },
        [&](const prt::tool::CommonOptions& common) {
            using namespace prt;
            const double start = tool::now_seconds();
            const scene::Scene sc = scene::load_scene(scene_path);
            if (sc.models.empty()) throw Error(scene_path + ": no models");
            std::vector<std::filesystem::path> pool_paths;
            std::vector<std::uint32_t> pool_of_model;
            for (const scene::Model& m : sc.models) {
                const std::filesystem::path p = std::filesystem::weakly_canonical(m.pool);
                auto it = std::find(pool_paths.begin(), pool_paths.end(), p);
                pool_of_model.push_back(static_cast<std::uint32_t>(it - pool_paths.begin()));
                if (it == pool_paths.end())
                    pool_paths.push_back(p);
                else
                    tool::note(common.quiet,
                               "prt-lightmap: pool %s placed more than once: its first placement is mapped",
                               p.string().c_str());
            }
            std::vector<std::optional<gi::GiOctree>> trees(pool_paths.size());
            std::uint64_t total_samples = 0;
            double trace_seconds = 0;
            gather.threads = threads;
            {
                // The RenderScene maps the pools rewritten below: it lives only in this scope.
                const rt::RenderScene rs = rt::RenderScene::load(sc);
                for (const std::string& w : rs.warnings())
                    tool::note(common.quiet, "prt-lightmap: %s", w.c_str());
                const core::SceneView view = rs.view();
                std::vector<bool> done(pool_paths.size(), false);
                for (std::size_t m = 0; m < rs.models().size(); ++m) {
                    const std::uint32_t p = pool_of_model[m];
                    if (done[p]) continue;
                    done[p] = true;
                    const pool::PoolFile& pf = *rs.models()[m].pool;
                    double root_min[3], root_size;
                    std::uint32_t depth;
                    gi::splat_root(pf, root_min, root_size, depth);
                    gather.depth = depth > levels_above ? depth - levels_above : 0;
                    std::vector<lightmap::Sample> samples = lightmap::select_samples(
                        pf, view.models[m], root_min, root_size, gather.depth, per_leaf);
                    const double t0 = tool::now_seconds();
                    {
                        tool::Progress progress("prt-lightmap: " + pool_paths[p].filename().string(),
                                                samples.size(), common.quiet);
                        lightmap::trace_samples(view, trace, samples, total_samples, threads,
                                                [&](std::uint64_t d) { progress.update(d); });
                        progress.finish();
                    }
                    trace_seconds += tool::now_seconds() - t0;
                    total_samples += samples.size();
                    trees[p] = lightmap::build_light_map_octree(samples, root_min, root_size, gather);
                    tool::note(
                        common.quiet,
                        "prt-lightmap: %s: %zu samples, level %u, %zu leaves, mean irradiance %.4g, max %.4g",
                        pool_paths[p].filename().string().c_str(), samples.size(), gather.depth,
                        trees[p]->leaves.size(), trees[p]->info.total[0], trees[p]->info.total[1]);
                }
            }
            const nlohmann::json parameters = {{"rays", trace.rays},
                                               {"bounces", trace.bounces},
                                               {"levels_above", levels_above},
                                               {"samples_per_leaf", per_leaf},
                                               {"gather_radius", gather.radius_edges},
                                               {"normal_reject", gather.reject_cos},
                                               {"seed", trace.seed},
                                               {"scene", scene_path}};
            for (std::size_t p = 0; p < pool_paths.size(); ++p)
                gi::write_gi_pool(pool_paths[p], gi::k_light_map_sections,
                                  trees[p] && !trees[p]->leaves.empty() ? &*trees[p] : nullptr,
                                  "prt-lightmap", parameters.dump());
            tool::note(common.quiet, "prt-lightmap: %llu samples x %u paths traced in %.3f s; total %.3f s",
                       static_cast<unsigned long long>(total_samples), trace.rays, trace_seconds,
                       tool::now_seconds() - start);
            if (!stats_json.empty()) {
                nlohmann::json per_pool = nlohmann::json::array();
                for (std::size_t p = 0; p < pool_paths.size(); ++p)
                    per_pool.push_back({{"pool", pool_paths[p].string()},
                                        {"leaves", trees[p] ? trees[p]->leaves.size() : 0},
                                        {"mean", trees[p] ? trees[p]->info.total[0] : 0.0f},
                                        {"max", trees[p] ? trees[p]->info.total[1] : 0.0f}});
                const nlohmann::json j = {{"tool", "prt-lightmap"},         {"scene", scene_path},
                                          {"parameters", parameters},       {"samples", total_samples},
                                          {"trace_seconds", trace_seconds}, {"pools", per_pool}};
                std::ofstream out(stats_json);
                out << j.dump(2) << "\n";
                if (!out) throw Error(stats_json + ": cannot write the statistics");
            }
        });
}
