// prt-radii: splat radius per point = distance to its k-th nearest neighbour (thesis 3.1).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "prt/pool_step.h"
#include "radii.h"

namespace {

constexpr const char* k_description =
    "Splat radii (thesis 3.1): each point's radius is the distance to its k-th nearest neighbour "
    "(exact k-NN: on the GPU when there is one, a Morton-ordered box tree, else a kd-tree over all cores; "
    "the radii are equal bit for bit). Outliers are clamped: with m the median raw radius of the "
    "point's k neighbours (--clamp-scope local) or of the whole model (global), radii above F*m become "
    "F*m "
    "(F = --clamp-factor): an isolated point among dense ones is clamped, a sparse region is not. Reads "
    "the positions of INPUT (local frame) and writes "
    "OUTPUT with a radii section; the other sections are carried over, an existing octree (which "
    "depends on the radii) is dropped. When the search does not fit --memory, it runs out of core "
    "(issue 17): tile by tile with a halo of neighbouring points, the sorted points, raw radii and "
    "neighbour lists in spill files (--spill-folder), with results equal to the in-core run.";

/// The out-of-core options of prt-radii.
struct MemoryOptions {
    std::string memory;        ///< --memory text; empty = half the physical memory
    std::string spill_folder;  ///< empty = the output's folder
    std::uint64_t tile_points = 0;
};

void report(const prt::tool::PoolStep& step, const prt::pre::RadiiParams& params,
            const prt::pre::RadiiStats& stats) {
    using namespace prt;
    step.note("prt-radii: %llu points, k = %u: radius min %.6g, median %.6g, mean %.6g, max %.6g",
              static_cast<unsigned long long>(stats.points), params.k, stats.min, stats.median, stats.mean,
              stats.max);
    if (params.clamp_factor > 0 && params.scope == pre::ClampScope::local)
        step.note("prt-radii: clamped %llu radii (%.3f%%) to %.3g x the median radius of their %u neighbours",
                  static_cast<unsigned long long>(stats.clamped),
                  100.0 * double(stats.clamped) / double(stats.points), double(params.clamp_factor),
                  params.k);
    else if (params.clamp_factor > 0)
        step.note("prt-radii: clamped %llu radii (%.3f%%) to %.3g x median %.6g = %.6g",
                  static_cast<unsigned long long>(stats.clamped),
                  100.0 * double(stats.clamped) / double(stats.points), double(params.clamp_factor),
                  stats.raw_median, stats.clamp_limit);
    else
        step.note("prt-radii: clamping off");
    if (stats.zero > 0)
        step.note(
            "prt-radii: warning: %llu points have radius 0 (k coincident neighbours); prt-octree skips "
            "them",
            static_cast<unsigned long long>(stats.zero));
}

void radii_step(prt::tool::PoolStep& step, prt::pre::RadiiParams params, const std::string& scope,
                const MemoryOptions& mem) {
    using namespace prt;
    const auto positions = step.input().require<pool::Float3>(pool::SectionType::positions, "prt-radii");
    const std::uint64_t peak_after_open = pre::peak_rss_bytes();
    if (positions.size() <= params.k)
        throw Error(step.input_path() + ": " + std::to_string(positions.size()) +
                    " points, need more than k = " + std::to_string(params.k) + " (lower --k)");
    params.scope = pre::parse_clamp_scope(scope);
    const std::uint64_t memory = tool::memory_limit(mem.memory);
    const std::uint64_t in_core = pre::radii_in_core_bytes(positions.size(), params);
    const std::string requested = params.backend;
    std::string why;
    const pre::RadiiPlan plan = pre::plan_radii(positions.size(), params, memory, mem.tile_points > 0, &why);
    params.backend = plan.backend;
    // (a small model's CPU search is the usual case: its "time (cpu)" line says it)
    if (requested == "auto" && params.backend == "cpu" &&
        pre::radii_gpu_pays(positions.size(), params.threads))
        step.note("prt-radii: --backend auto: using the CPU (%s)", why.c_str());
    const bool tiled = plan.tiled;
    tool::Progress progress(tiled                      ? "prt-radii: k-NN search by tiles"
                            : params.backend == "cuda" ? "prt-radii: k-NN search (CUDA)"
                                                       : "prt-radii: k-NN search",
                            positions.size(), step.quiet());
    pre::RadiiStats stats;
    pre::TiledKnnStats tstats;
    std::uint64_t peak_before_write = 0;
    const bool dropped_octree =
        step.drop_sections({pool::SectionType::octree_info, pool::SectionType::octree_nodes,
                            pool::SectionType::leaf_info, pool::SectionType::splats});
    if (tiled) {
        pre::TiledKnnParams tiling;
        tiling.memory = memory;
        tiling.tile_points = mem.tile_points;
        tiling.positions_mapped = true;  // the input pool's positions section
        tiling.spill_folder = !mem.spill_folder.empty()
                                  ? std::filesystem::path(mem.spill_folder)
                                  : std::filesystem::absolute(step.output_path()).parent_path();
        step.note("prt-radii: out of core: the search needs about %s, --memory is %s; spill files in %s",
                  tool::format_bytes(in_core).c_str(), tool::format_bytes(memory).c_str(),
                  tiling.spill_folder.string().c_str());
        auto spill = std::make_shared<pre::SpillFile>(step.about_input([&] {
            return pre::compute_radii_tiled(positions, params, tiling, &stats, &tstats,
                                            [&](std::uint64_t done) { progress.update(done); });
        }));
        progress.finish();
        peak_before_write = pre::peak_rss_bytes();
        step.writer().add_view(pool::SectionType::radii, sizeof(float), positions.size(),
                               {spill->data(), static_cast<std::size_t>(spill->size())},
                               std::shared_ptr<const void>(spill, spill->data()), true);
        step.note(
            "prt-radii: %llu tiles of about %llu points; %llu points needed a halo (%llu groups, %llu "
            "scanned alone); at most %llu points held at once",
            static_cast<unsigned long long>(tstats.tiles),
            static_cast<unsigned long long>(tstats.tile_points),
            static_cast<unsigned long long>(tstats.halo_queries),
            static_cast<unsigned long long>(tstats.halo_groups),
            static_cast<unsigned long long>(tstats.scanned),
            static_cast<unsigned long long>(tstats.max_gathered));
    } else {
        std::vector<float> radii = step.about_input([&] {
            return pre::compute_radii(positions, params, &stats,
                                      [&](std::uint64_t done) { progress.update(done); });
        });
        progress.finish();
        peak_before_write = pre::peak_rss_bytes();
        step.writer().add_array(pool::SectionType::radii, std::move(radii));
    }
    const nlohmann::json parameters = {
        {"k", params.k}, {"clamp_factor", params.clamp_factor}, {"clamp_scope", scope}};
    const std::uint64_t bytes = step.write(parameters);

    const double total_seconds = step.seconds();
    step.write_stats({{"points", stats.points},
                      {"parameters", parameters},
                      {"min", stats.min},
                      {"median", stats.median},
                      {"mean", stats.mean},
                      {"max", stats.max},
                      {"raw_median", stats.raw_median},
                      {"clamp_limit", stats.clamp_limit},
                      {"clamped", stats.clamped},
                      {"zero", stats.zero},
                      {"index_seconds", stats.seconds_index},
                      {"search_seconds", stats.seconds_search},
                      {"radii_seconds", stats.seconds},
                      {"total_seconds", total_seconds},
                      {"out_of_core", tiled},
                      {"backend", stats.backend},
                      {"memory", memory},
                      {"tiles", tstats.tiles},
                      {"halo_points", tstats.halo_queries},
                      {"halo_groups", tstats.halo_groups},
                      {"halo_gathered", tstats.gathered},
                      {"scanned", tstats.scanned},
                      {"max_gathered", tstats.max_gathered},
                      {"peak_rss", pre::peak_rss_bytes()},
                      {"peak_rss_before_write", peak_before_write},
                      {"peak_rss_after_open", peak_after_open},
                      {"peak_anon_rss_search", tstats.peak_anon_rss}});
    report(step, params, stats);
    if (dropped_octree) step.note("prt-radii: dropped the input's octree sections (rerun prt-octree)");
    step.note("prt-radii: time (%s): index %.3f s, search %.3f s, total %.3f s; wrote %s (%llu bytes)",
              stats.backend.c_str(), stats.seconds_index, stats.seconds_search, total_seconds,
              step.output_path().c_str(), static_cast<unsigned long long>(bytes));
}

}  // namespace

int main(int argc, char** argv) {
    prt::pre::RadiiParams params;
    params.backend = "auto";
    std::string scope = "local";
    MemoryOptions mem;
    prt::tool::PoolStep step("prt-radii", k_description,
                             {.stats = "Also write the statistics as JSON to this file (benchmarks)"});
    return step.run(
        argc, argv,
        [&](CLI::App& app) {
            app.add_option("-k,--k", params.k,
                           "Neighbour count k: the radius is the distance to the k-th nearest neighbour")
                ->check(CLI::Range(1u, 1024u));
            app.add_option("--clamp-factor", params.clamp_factor,
                           "Clamp radii above this factor times the median radius of --clamp-scope to that "
                           "value (0 = no clamping)")
                ->check(CLI::Range(0.0f, 1.0e6f));
            app.add_option(
                   "--clamp-scope", scope,
                   "local: the median raw radius of the point's k neighbours (uneven scans keep their "
                   "sparse regions); global: the whole model's median radius")
                ->check(CLI::IsMember({"local", "global"}));
            prt::tool::PoolStep::add_memory(
                app, mem.memory,
                "Memory the k-NN search may use (K, M, G suffixes: 512M, 4G); above it the CPU search "
                "runs out of core, tile by tile; the CUDA search keeps 4 bytes per point here "
                "(default: half the physical memory)");
            app.add_option("--spill-folder", mem.spill_folder,
                           "Folder of the out-of-core spill files (removed as soon as created; about "
                           "16 + 8 + 4k bytes per point) (default: the output's folder)");
            app.add_option("--tile-points", mem.tile_points,
                           "Testing: force the out-of-core search with tiles of this many points")
                ->group("");
            app.add_option("--backend", params.backend,
                           "auto (CUDA when a device can hold the search and the model has 100k points per "
                           "CPU thread or more, else CPU), cpu or cuda; the radii are the same. The CUDA "
                           "search needs about 40 bytes per point of device "
                           "memory and k <= 32")
                ->check(CLI::IsMember({"auto", "cpu", "cuda"}));
            prt::tool::PoolStep::add_threads(app, params.threads,
                                             "CPU worker threads (0 = every core the process may use)");
        },
        [&](prt::tool::PoolStep& s) { radii_step(s, params, scope, mem); });
}
