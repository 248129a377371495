// prt-cull: probe-ray culling of replicated splats (thesis 3.4), with an optional hole-rate
// measurement of what the culling cost.
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "cull_build.h"
#include "prt/pool_step.h"

namespace {

nlohmann::json counts_json(const prt::pre::HoleCounts& c) {
    return {{"rays", c.rays},
            {"hit_unculled", c.hit_full},
            {"on_surface", c.on_surface},
            {"holes", c.holes()},
            {"hole_rate", c.hole_rate()},
            {"missed", c.missed},
            {"wrong_surface", c.wrong_surface},
            {"spurious", c.spurious},
            {"mean_normal_error_degrees", c.mean_normal_error()}};
}

constexpr const char* k_description =
    "Probe-ray culling (thesis 3.4): removes the replicated splats of INPUT's octree (prt-octree stores "
    "every splat in every leaf its disk overlaps) that no probe ray needs. Per filled leaf, probe lines "
    "along --directions directions (spread over a hemisphere, randomly rotated per leaf), each a "
    "jittered --grid x --grid grid of parallel lines across the part of the leaf its disks reach, are "
    "walked through the octree and intersected with the leaf's splats by the renderer's own functions; "
    "each line is a probe ray both ways. Splats whose centre lies in "
    "the leaf are always kept; a replica is kept when a probe needs it (--policy). The node pool is "
    "unchanged; leaf_info, splats and octree_info (k_octree_culled) are rewritten, the other sections "
    "carried over. --measure-holes N then shoots N rays at INPUT and OUTPUT and reports the rays that "
    "hit the unculled surface but miss the culled one or hit it 3 mean splat radii away or more (a ray whose "
    "unculled hit lies within 3 mean radii of its origin starts inside the surface's band and is not "
    "counted).";

using ull = unsigned long long;

/// INPUT's replicated octree.
prt::pre::OctreeSections read_octree(prt::tool::PoolStep& step) {
    using namespace prt;
    const pool::PoolFile& in = step.input();
    const std::string& input = step.input_path();
    if (!in.has(pool::SectionType::octree_info)) throw Error(input + ": no octree: run prt-octree first");
    pre::OctreeSections sections;
    sections.info = in.require<pool::OctreeInfo>(pool::SectionType::octree_info, "prt-cull")[0];
    sections.nodes = in.require<std::uint32_t>(pool::SectionType::octree_nodes, "prt-cull");
    sections.leaf_info = in.require<std::uint32_t>(pool::SectionType::leaf_info, "prt-cull");
    sections.splats = in.require<pool::Splat>(pool::SectionType::splats, "prt-cull");
    if ((sections.info.flags & pool::k_octree_replicated) == 0)
        throw Error(input + ": the octree is not replicated (prt-octree --no-replicate): nothing to cull");
    if (sections.info.flags & pool::k_octree_culled)
        step.note("prt-cull: %s is culled already; culling its remaining replicas", input.c_str());
    return sections;
}

void report(const prt::tool::PoolStep& step, const prt::pre::CullStats& stats, std::uint64_t bytes_before,
            std::uint64_t bytes, double total_seconds) {
    const double mib = 1.0 / (1024.0 * 1024.0);
    step.note("prt-cull: backend %s", stats.backend.c_str());
    step.note(
        "prt-cull: splats %llu -> %llu (%llu centre splats, replicas %llu -> %llu); per unique splat "
        "%.3f -> %.3f",
        ull(stats.splats_before), ull(stats.splats_after), ull(stats.centre_splats),
        ull(stats.replicas_before), ull(stats.replicas_kept), stats.replication_before(),
        stats.replication_after());
    step.note("prt-cull: splat memory %.1f -> %.1f MiB (leaf_info + splats); pool %.1f -> %.1f MiB",
              double(stats.bytes_before) * mib, double(stats.bytes_after) * mib, double(bytes_before) * mib,
              double(bytes) * mib);
    step.note(
        "prt-cull: %llu probe rays reached their leaf, %llu hit a splat, %llu kept a replica; culling "
        "%.3f s, total %.3f s; wrote %s",
        ull(stats.counters.probes), ull(stats.counters.probes_hit), ull(stats.counters.probes_unserved),
        stats.seconds, total_seconds, step.output_path().c_str());
}

void report_holes(const prt::tool::PoolStep& step, const prt::pre::HoleStats& hs) {
    using namespace prt;
    for (std::uint32_t f = 0; f < pre::k_hole_families; ++f) {
        const pre::HoleCounts& c = hs.family[f];
        step.note(
            "prt-cull: holes %-6s %llu of %llu rays hitting the unculled surface (%.4f %%: %llu miss, "
            "%llu hit another surface), mean normal change %.2f deg; %llu rays starting on the surface "
            "not counted",
            pre::hole_family_name(static_cast<pre::HoleFamily>(f)), ull(c.holes()), ull(c.hit_full),
            100.0 * c.hole_rate(), ull(c.missed), ull(c.wrong_surface), c.mean_normal_error(),
            ull(c.on_surface));
    }
    step.note("prt-cull: hole rate %.4f %% (%llu of %llu hitting rays, %llu rays, %s, %.3f s)",
              100.0 * hs.total.hole_rate(), ull(hs.total.holes()), ull(hs.total.hit_full), ull(hs.total.rays),
              hs.backend.c_str(), hs.seconds);
}

nlohmann::json stats_json(const prt::pre::CullStats& stats) {
    return {{"device", stats.backend},
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
            {"probes", stats.counters.probes},
            {"probes_hit", stats.counters.probes_hit},
            {"probes_unserved", stats.counters.probes_unserved},
            {"splat_tests", stats.counters.splat_tests},
            {"cull_seconds", stats.seconds}};
}

nlohmann::json holes_json(const prt::pre::HoleStats& hs, const prt::pre::HoleParams& holes) {
    using namespace prt;
    nlohmann::json h = {{"total", counts_json(hs.total)},
                        {"device", hs.backend},
                        {"seed", holes.seed},
                        {"seconds", hs.seconds}};
    for (std::uint32_t f = 0; f < pre::k_hole_families; ++f)
        h[pre::hole_family_name(static_cast<pre::HoleFamily>(f))] = counts_json(hs.family[f]);
    return h;
}

void cull_step(prt::tool::PoolStep& step, prt::pre::CullParams params, prt::pre::HoleParams holes,
               const std::string& policy) {
    using namespace prt;
    params.policy = policy == "thesis"  ? pre::CullPolicy::thesis
                    : policy == "votes" ? pre::CullPolicy::votes
                                        : pre::CullPolicy::greedy;
    std::future<void> device = pre::warm_up_cull_backend(params.backend);  // while the input is read
    const pre::OctreeSections sections = read_octree(step);
    std::string why;
    const std::string backend = pre::resolve_cull_backend(params.backend, &why);
    if (params.backend == "auto" && backend == "cpu")
        step.note("prt-cull: --backend auto: using the CPU (%s)", why.c_str());
    params.backend = backend;

    step.note(
        "prt-cull: %u filled leaves, %llu stored splats; %u directions x %u x %u = %u probe lines (each "
        "both ways) per leaf, %s policy",
        sections.info.filled_leaves, ull(sections.splats.size()), params.directions, params.grid, params.grid,
        params.directions * params.grid * params.grid, policy.c_str());
    pre::CullStats stats;
    pre::CulledOctree culled;
    {
        tool::Progress progress("prt-cull: probing", sections.info.filled_leaves, step.quiet());
        params.progress = [&](std::uint64_t done, std::uint64_t) { progress.update(done); };
        culled = step.about_input([&] { return pre::cull_octree(sections, params, &stats); });
        progress.finish();
    }

    pool::PoolWriter& writer = step.writer();
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
        step.note("prt-cull: measuring holes with %llu rays", ull(holes.rays));
        hs = pre::measure_holes(sections, culled_view, holes);
    }
    // The GPU is done: its context goes while the pool is written (joined before returning).
    std::future<void> released = pre::release_cull_backend(backend);
    const nlohmann::json parameters = {{"directions", params.directions},
                                       {"grid", params.grid},
                                       {"probes_per_leaf", params.directions * params.grid * params.grid},
                                       {"policy", policy},
                                       {"window", params.window},
                                       {"seed", params.seed},
                                       {"backend", backend}};
    writer.add_array(pool::SectionType::octree_info, std::vector<pool::OctreeInfo>{culled.info});
    writer.add_array(pool::SectionType::leaf_info, std::move(culled.leaf_info));
    writer.add_array(pool::SectionType::splats, std::move(culled.splats));
    const std::uint64_t bytes = step.write(parameters);
    released.get();
    const double total_seconds = step.seconds();

    report(step, stats, step.input().file_size(), bytes, total_seconds);
    if (holes.rays > 0) report_holes(step, hs);
    nlohmann::json j = stats_json(stats);
    j["input"] = step.input_path();
    j["parameters"] = parameters;
    j["pool_bytes_before"] = step.input().file_size();
    j["pool_bytes_after"] = bytes;
    j["total_seconds"] = total_seconds;
    if (holes.rays > 0) j["holes"] = holes_json(hs, holes);
    step.write_stats(std::move(j));
}

}  // namespace

int main(int argc, char** argv) {
    std::string policy = "greedy";
    prt::pre::CullParams params;
    prt::pre::HoleParams holes;
    holes.rays = 0;
    prt::tool::PoolStep step("prt-cull", k_description,
                             {.input = "Input pool file with a replicated octree (prt-octree)"});
    return step.run(
        argc, argv,
        [&](CLI::App& app) {
            app.add_option(
                   "--directions", params.directions,
                   "Probe line directions per leaf, spread over a hemisphere; each line is probed both ways")
                ->check(CLI::Range(1u, 256u));
            app.add_option("--grid", params.grid,
                           "G: a jittered G x G grid of parallel probe lines per direction")
                ->check(CLI::Range(1u, 64u));
            app.add_option(
                   "--policy", policy,
                   "Which replicas survive: 'greedy' (probes test the splats kept so far; an unserved "
                   "probe keeps the one replica it hits nearest that disk's centre), 'votes' (greedy, "
                   "keeping the replica most unserved probes hit) or 'thesis' (every replica hit by a "
                   "probe that misses the leaf's centre splats)")
                ->check(CLI::IsMember({"greedy", "votes", "thesis"}));
            app.add_option("--window", params.window,
                           "Blending window in radii of the nearest splat (the renderer's blend_window): a "
                           "probe is served when a kept splat is hit within it")
                ->check(CLI::Range(1e-3f, 100.0f));
            app.add_option("--seed", params.seed, "Seed of the probe jitter and direction rotations");
            app.add_option("--backend", params.backend,
                           "auto (CUDA when a device is usable, else CPU), cpu or cuda")
                ->check(CLI::IsMember({"auto", "cpu", "cuda"}));
            prt::tool::PoolStep::add_threads(app, params.threads,
                                             "CPU worker threads (0 = every core the process may use)");
            app.add_option(
                "--measure-holes", holes.rays,
                "After culling, shoot N rays at INPUT and OUTPUT and report the hole rate: rays that "
                "hit the unculled surface but miss the culled one there (0 = off). 40 % go from the "
                "bounding sphere into the bounds, 10 % the same as inside rays (back faces, as "
                "refracted rays), 25 % from 64 x 64 views outside, 25 % from 64 x 64 views inside "
                "the bounds");
            app.add_option("--hole-seed", holes.seed, "Seed of the hole-measurement rays");
        },
        [&](prt::tool::PoolStep& s) { cull_step(s, params, holes, policy); });
}
