// prt-cull: probe-ray culling of replicated splats (thesis 3.4), with an optional hole-rate
// measurement of what the culling cost.
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cull.h"
#include "prt/formats/pool.h"
#include "prt/tool.h"

namespace {

nlohmann::json counts_json(const prt::pre::HoleCounts& c) {
    return {{"rays", c.rays},         {"hit_unculled", c.hit_full},
            {"holes", c.holes()},     {"hole_rate", c.hole_rate()},
            {"missed", c.missed},     {"wrong_surface", c.wrong_surface},
            {"spurious", c.spurious}, {"mean_normal_error_degrees", c.mean_normal_error()}};
}

}  // namespace

int main(int argc, char** argv) {
    std::string input, output, policy = "greedy", stats_json;
    prt::pre::CullParams params;
    prt::pre::HoleParams holes;
    holes.rays = 0;
    return prt::tool::run(
        argc, argv, "prt-cull",
        "Probe-ray culling (thesis 3.4): removes the replicated splats of INPUT's octree (prt-octree stores "
        "every splat in every leaf its disk overlaps) that no probe ray needs. Per filled leaf, probe lines "
        "along --directions directions (spread over a hemisphere, randomly rotated per leaf), each a "
        "jittered --grid x --grid grid of parallel lines across the part of the leaf its disks reach, are "
        "walked through the octree and intersected with the leaf's splats by the renderer's own functions; "
        "each line is a probe ray both ways. Splats whose centre lies in "
        "the leaf are always kept; a replica is kept when a probe needs it (--policy). The node pool is "
        "unchanged; leaf_info, splats and octree_info (k_octree_culled) are rewritten, the other sections "
        "carried over. --measure-holes N then shoots N rays at INPUT and OUTPUT and reports the rays that "
        "hit the unculled surface but miss the culled one.",
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("input", input, "Input pool file with a replicated octree (prt-octree)")
                ->required();
            app.add_option("-o,--output", output, "Output pool file (written atomically; may equal INPUT)")
                ->required();
            app.add_option(
                   "--directions", params.directions,
                   "Probe line directions per leaf, spread over a hemisphere; each line is probed both ways")
                ->check(CLI::Range(1u, 256u))
                ->capture_default_str();
            app.add_option("--grid", params.grid,
                           "G: a jittered G x G grid of parallel probe lines per direction")
                ->check(CLI::Range(1u, 64u))
                ->capture_default_str();
            app.add_option(
                   "--policy", policy,
                   "Which replicas survive: 'greedy' (probes test the splats kept so far; an unserved "
                   "probe keeps the one replica it hits nearest that disk's centre), 'votes' (greedy, "
                   "keeping the replica most unserved probes hit) or 'thesis' (every replica hit by a "
                   "probe that misses the leaf's centre splats)")
                ->check(CLI::IsMember({"greedy", "votes", "thesis"}))
                ->capture_default_str();
            app.add_option("--window", params.window,
                           "Blending window in radii of the nearest splat (the renderer's blend_window): a "
                           "probe is served when a kept splat is hit within it")
                ->check(CLI::Range(1e-3f, 100.0f))
                ->capture_default_str();
            app.add_option("--seed", params.seed, "Seed of the probe jitter and direction rotations")
                ->capture_default_str();
            app.add_option("--backend", params.backend,
                           "auto (CUDA when a device is usable, else CPU), cpu or cuda")
                ->check(CLI::IsMember({"auto", "cpu", "cuda"}))
                ->capture_default_str();
            app.add_option("-j,--threads", params.threads, "CPU worker threads (0 = all hardware threads)")
                ->capture_default_str();
            app.add_option(
                   "--measure-holes", holes.rays,
                   "After culling, shoot N rays at INPUT and OUTPUT and report the hole rate: rays that hit "
                   "the unculled surface but miss the culled one there (0 = off). 40 % go from the bounding "
                   "sphere into the bounds, 10 % the same as inside rays (back faces, as refracted rays), 25 "
                   "% "
                   "from 64 x 64 views outside, 25 % from 64 x 64 views inside the bounds")
                ->capture_default_str();
            app.add_option("--hole-seed", holes.seed, "Seed of the hole-measurement rays")
                ->capture_default_str();
            app.add_option("--stats-json", stats_json, "Also write the statistics as JSON to this file");
        },
        [&](const prt::tool::CommonOptions& common) {
            using namespace prt;
            const double start = tool::now_seconds();
            params.policy = policy == "thesis"  ? pre::CullPolicy::thesis
                            : policy == "votes" ? pre::CullPolicy::votes
                                                : pre::CullPolicy::greedy;
            const pool::PoolFile in = pool::PoolFile::open(input);
            if (!in.has(pool::SectionType::octree_info))
                throw Error(input + ": no octree: run prt-octree first");
            pre::OctreeSections sections;
            sections.info = in.require<pool::OctreeInfo>(pool::SectionType::octree_info, "prt-cull")[0];
            sections.nodes = in.require<std::uint32_t>(pool::SectionType::octree_nodes, "prt-cull");
            sections.leaf_info = in.require<std::uint32_t>(pool::SectionType::leaf_info, "prt-cull");
            sections.splats = in.require<pool::Splat>(pool::SectionType::splats, "prt-cull");
            if ((sections.info.flags & pool::k_octree_replicated) == 0)
                throw Error(input +
                            ": the octree is not replicated (prt-octree --no-replicate): nothing to cull");
            if (sections.info.flags & pool::k_octree_culled)
                tool::note(common.quiet, "prt-cull: %s is culled already; culling its remaining replicas",
                           input.c_str());
            std::string why;
            const std::string backend = pre::resolve_cull_backend(params.backend, &why);
            if (params.backend == "auto" && backend == "cpu")
                tool::note(common.quiet, "prt-cull: --backend auto: using the CPU (%s)", why.c_str());
            params.backend = backend;

            tool::note(
                common.quiet,
                "prt-cull: %u filled leaves, %llu stored splats; %u directions x %u x %u = %u probe lines "
                "(each both ways) per leaf, %s policy",
                sections.info.filled_leaves, static_cast<unsigned long long>(sections.splats.size()),
                params.directions, params.grid, params.grid, params.directions * params.grid * params.grid,
                policy.c_str());
            pre::CullStats stats;
            pre::CulledOctree culled;
            {
                tool::Progress progress("prt-cull: probing", sections.info.filled_leaves, common.quiet);
                params.progress = [&](std::uint64_t done, std::uint64_t) { progress.update(done); };
                try {
                    culled = pre::cull_octree(sections, params, &stats);
                } catch (const Error& e) {
                    throw Error(input + ": " + e.what());
                }
                progress.finish();
            }

            pool::PoolWriter writer;
            writer.carry_over(in);
            pre::OctreeSections culled_view;
            culled_view.info = culled.info;
            culled_view.nodes = sections.nodes;
            culled_view.leaf_info = culled.leaf_info;
            culled_view.splats = culled.splats;
            // Hole measurement before the write hands the arrays to the writer.
            pre::HoleStats hs;
            if (holes.rays > 0) {
                holes.window = params.window;
                holes.threads = params.threads;
                holes.backend = backend;
                tool::note(common.quiet, "prt-cull: measuring holes with %llu rays",
                           static_cast<unsigned long long>(holes.rays));
                hs = pre::measure_holes(sections, culled_view, holes);
            }
            const nlohmann::json parameters = {
                {"directions", params.directions},
                {"grid", params.grid},
                {"probes_per_leaf", params.directions * params.grid * params.grid},
                {"policy", policy},
                {"window", params.window},
                {"seed", params.seed},
                {"backend", backend}};
            writer.add_array(pool::SectionType::octree_info, std::vector<pool::OctreeInfo>{culled.info});
            writer.add_array(pool::SectionType::leaf_info, std::move(culled.leaf_info));
            writer.add_array(pool::SectionType::splats, std::move(culled.splats));
            writer.add_provenance("prt-cull", PRT_VERSION, parameters.dump());
            const std::uint64_t bytes = writer.write(output);
            const double total_seconds = tool::now_seconds() - start;

            const double mib = 1.0 / (1024.0 * 1024.0);
            tool::note(common.quiet, "prt-cull: backend %s", stats.backend.c_str());
            tool::note(
                common.quiet,
                "prt-cull: splats %llu -> %llu (%llu centre splats, replicas %llu -> %llu); per unique "
                "splat %.3f -> %.3f",
                static_cast<unsigned long long>(stats.splats_before),
                static_cast<unsigned long long>(stats.splats_after),
                static_cast<unsigned long long>(stats.centre_splats),
                static_cast<unsigned long long>(stats.replicas_before),
                static_cast<unsigned long long>(stats.replicas_kept), stats.replication_before(),
                stats.replication_after());
            tool::note(common.quiet,
                       "prt-cull: splat memory %.1f -> %.1f MiB (leaf_info + splats); pool %.1f -> %.1f MiB",
                       double(stats.bytes_before) * mib, double(stats.bytes_after) * mib,
                       double(in.file_size()) * mib, double(bytes) * mib);
            tool::note(common.quiet,
                       "prt-cull: %llu probe rays reached their leaf, %llu hit a splat, %llu kept a replica; "
                       "culling %.3f s, total %.3f s; wrote %s",
                       static_cast<unsigned long long>(stats.counters.probes),
                       static_cast<unsigned long long>(stats.counters.probes_hit),
                       static_cast<unsigned long long>(stats.counters.probes_unserved), stats.seconds,
                       total_seconds, output.c_str());
            if (holes.rays > 0) {
                for (std::uint32_t f = 0; f < pre::k_hole_families; ++f) {
                    const pre::HoleCounts& c = hs.family[f];
                    tool::note(
                        common.quiet,
                        "prt-cull: holes %-6s %llu of %llu rays hitting the unculled surface (%.4f %%: "
                        "%llu miss, %llu hit another surface), mean normal change %.2f deg",
                        pre::hole_family_name(static_cast<pre::HoleFamily>(f)),
                        static_cast<unsigned long long>(c.holes()),
                        static_cast<unsigned long long>(c.hit_full), 100.0 * c.hole_rate(),
                        static_cast<unsigned long long>(c.missed),
                        static_cast<unsigned long long>(c.wrong_surface), c.mean_normal_error());
                }
                tool::note(common.quiet,
                           "prt-cull: hole rate %.4f %% (%llu of %llu hitting rays, %llu rays, %s, %.3f s)",
                           100.0 * hs.total.hole_rate(), static_cast<unsigned long long>(hs.total.holes()),
                           static_cast<unsigned long long>(hs.total.hit_full),
                           static_cast<unsigned long long>(hs.total.rays), hs.backend.c_str(), hs.seconds);
            }
            if (!stats_json.empty()) {
                nlohmann::json j = {{"tool", "prt-cull"},
                                    {"input", input},
                                    {"parameters", parameters},
                                    {"device", stats.backend},
                                    {"leaves", stats.leaves},
                                    {"leaves_with_replicas", stats.leaves_with_replicas},
                                    {"unique_splats", stats.unique_splats},
                                    {"splats_before", stats.splats_before},
                                    {"splats_after", stats.splats_after},
                                    {"centre_splats", stats.centre_splats},
                                    {"replicas_before", stats.replicas_before},
                                    {"replicas_kept", stats.replicas_kept},
                                    {"replication_before", stats.replication_before()},
                                    {"replication_after", stats.replication_after()},
                                    {"splat_bytes_before", stats.bytes_before},
                                    {"splat_bytes_after", stats.bytes_after},
                                    {"pool_bytes_before", in.file_size()},
                                    {"pool_bytes_after", bytes},
                                    {"probes", stats.counters.probes},
                                    {"probes_hit", stats.counters.probes_hit},
                                    {"probes_unserved", stats.counters.probes_unserved},
                                    {"splat_tests", stats.counters.splat_tests},
                                    {"cull_seconds", stats.seconds},
                                    {"total_seconds", total_seconds}};
                if (holes.rays > 0) {
                    nlohmann::json h = {{"total", counts_json(hs.total)},
                                        {"device", hs.backend},
                                        {"seed", holes.seed},
                                        {"seconds", hs.seconds}};
                    for (std::uint32_t f = 0; f < pre::k_hole_families; ++f)
                        h[pre::hole_family_name(static_cast<pre::HoleFamily>(f))] = counts_json(hs.family[f]);
                    j["holes"] = h;
                }
                std::ofstream out(stats_json);
                out << j.dump(2) << "\n";
                if (!out) throw Error(stats_json + ": cannot write the statistics");
            }
        });
}
