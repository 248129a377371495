// prt-bricks: cuts the splat octree into bricks of compressed splats with a level-of-detail disc per
// top node (issue 17; format in formats/POOL.md, "Bricks and level of detail").
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "brick_build.h"
#include "bricks_from_points.h"
#include "prt/formats/octree_sections.h"
#include "prt/pool_step.h"
#include "prt/tool.h"
#include "radii.h"

namespace {

/// Bytes of one LOD prefix node: its word (lod_nodes) and its disc (lod_discs).
constexpr std::uint64_t k_lod_node_bytes = sizeof(std::uint32_t) + sizeof(prt::pool::CompressedSplat);

constexpr const char* k_description =
    "Cuts INPUT's splat octree (prt-octree, prt-cull) into a small resident top tree and bricks: "
    "greedily from the root, a node whose subtree holds at most --brick-splats stored splats "
    "(replicas counted) becomes a brick, stored contiguously (64-byte aligned) with its own nodes, "
    "leaf ranges, splats compressed to 12 bytes (16-bit positions in the brick's cube, octahedral "
    "normals, radii rounded up on a log scale, RGB565 colours), each stored once per brick however many "
    "of its leaves hold it (leaves reference splats by 16-bit index), and its own checksum, so it can be "
    "read, checked and uploaded alone. Every top node gets a level-of-detail disc covering its splats. "
    "The float octree sections (octree_info, octree_nodes, leaf_info, splats) are removed unless "
    "--keep-float, the per-point sections (positions, normals, colors, radii, material_ids, "
    "intensities, scan_ids) unless --keep-points: a streaming pool needs neither, tools that read "
    "points (prt-iso, prt-mls, prt-fidelity) do. Other sections are carried over. Material ids and "
    "intensities are not carried into bricks. Reports the codec's error against the float splats.\n\n"
    "Given a pool without an octree but with radii (prt-radii), prt-bricks builds the octree, culls it "
    "and cuts it itself, out of core: the model is partitioned into octree cells that each fit in "
    "--memory and each cell's subtree is built, culled and cut alone, the points and payloads going "
    "through spill files; the result equals prt-octree -> prt-cull -> prt-bricks with the same "
    "options byte for byte. Given points and normals without radii (prt-import), it first computes "
    "the radii as prt-radii does with its defaults (k = 9, local clamp at 3; on the GPU when there is "
    "one, else on the CPU, out of core above --memory), the same radii, without writing and reading "
    "them back as a pool.";

/// The radii of a pool that has none, as prt-radii computes them with its defaults (in memory, or
/// in a spill file when the CPU's search runs out of core), and what the provenance records.
struct OwnRadii {
    std::vector<float> values;
    prt::pre::SpillFile spill;
    std::span<const float> radii;
    nlohmann::json parameters;  ///< for the provenance
    nlohmann::json stats;       ///< for --stats-json
};

OwnRadii compute_own_radii(prt::tool::PoolStep& step, std::span<const prt::pool::Float3> positions,
                           unsigned threads, std::uint64_t memory,
                           const std::filesystem::path& spill_folder) {
    using namespace prt;
    OwnRadii out;
    pre::RadiiParams rp;  // prt-radii's defaults
    rp.threads = threads;
    rp.backend = "auto";
    const pre::RadiiPlan plan = pre::plan_radii(positions.size(), rp, memory, false);
    rp.backend = plan.backend;
    const bool tiled = plan.tiled;
    pre::RadiiStats rs;
    {
        tool::Progress progress("prt-bricks: k-NN radii (no radii in the input)", positions.size(),
                                step.quiet());
        const auto update = [&](std::uint64_t done) { progress.update(done); };
        if (tiled) {
            pre::TiledKnnParams tiling;
            tiling.memory = memory;
            tiling.positions_mapped = step.input().mapped();
            tiling.spill_folder = spill_folder;
            out.spill = step.about_input(
                [&] { return pre::compute_radii_tiled(positions, rp, tiling, &rs, nullptr, update); });
            out.radii = out.spill.as<const float>();
        } else {
            out.values = step.about_input([&] { return pre::compute_radii(positions, rp, &rs, update); });
            out.radii = out.values;
        }
        progress.finish();
    }
    step.note(
        "prt-bricks: no radii in the input: computed them as prt-radii does (k = %u, clamp %g x the median "
        "of the point's neighbours; %s%s): median %.6g, %llu clamped, %.1f s",
        rp.k, double(rp.clamp_factor), rs.backend.c_str(), tiled ? ", out of core" : "", rs.median,
        static_cast<unsigned long long>(rs.clamped), rs.seconds);
    // what decides the radii (the backend does not: its radii are the same)
    out.parameters = {
        {"k", rp.k}, {"clamp_factor", rp.clamp_factor}, {"clamp_scope", pre::clamp_scope_name(rp.scope)}};
    out.stats = {{"backend", rs.backend},
                 {"seconds", rs.seconds},
                 {"seconds_index", rs.seconds_index},
                 {"seconds_search", rs.seconds_search},
                 {"median", rs.median},
                 {"clamped", rs.clamped}};
    return out;
}

/// The options of the build from points (out of core).
struct PointOptions {
    prt::pre::PointBrickParams params;
    bool no_cull = false;
    std::string policy = "greedy";
    std::string memory;         ///< --memory text; empty = half the physical memory
    std::string spill_folder;   ///< empty = the output's folder
    std::string stage = "all";  ///< --stage: all, plan, cells or merge (the staged build, issue 21)
    std::string cells_folder;   ///< --cells-folder: the staged build's shared folder
    std::string cells;          ///< --cells A:B (stage cells)
};

/// --direct's words and what they select (the option's value is looked up here, provenance names it).
const std::map<std::string, prt::pre::BrickParams::Direct> k_direct_words = {
    {"smaller", prt::pre::BrickParams::Direct::smaller},
    {"always", prt::pre::BrickParams::Direct::always},
    {"never", prt::pre::BrickParams::Direct::never}};

const char* direct_policy_name(prt::pre::BrickParams::Direct d) {
    for (const auto& [word, value] : k_direct_words)
        if (value == d) return word.c_str();
    return "smaller";
}

/// --cells "A:B" as [A, B).
std::pair<std::uint32_t, std::uint32_t> parse_cells(const std::string& text) {
    const std::size_t colon = text.find(':');
    try {
        if (colon != std::string::npos && colon > 0 && colon + 1 < text.size()) {
            std::size_t used_a = 0, used_b = 0;
            const unsigned long a = std::stoul(text.substr(0, colon), &used_a);
            const unsigned long b = std::stoul(text.substr(colon + 1), &used_b);
            if (used_a == colon && used_b == text.size() - colon - 1 && a < b && b <= 0xFFFFFFFFul)
                return {std::uint32_t(a), std::uint32_t(b)};
        }
    } catch (const std::exception&) {
    }
    throw prt::Error("--cells '" + text +
                     "': expected FIRST:LAST with FIRST < LAST (cells FIRST to LAST - 1)");
}

constexpr prt::pool::SectionType k_point_sections[] = {
    prt::pool::SectionType::positions,    prt::pool::SectionType::normals,
    prt::pool::SectionType::colors,       prt::pool::SectionType::radii,
    prt::pool::SectionType::material_ids, prt::pool::SectionType::intensities,
    prt::pool::SectionType::scan_ids};

using ull = unsigned long long;

nlohmann::json error_json(const prt::pre::CodecError& e) {
    const double n = e.splats ? double(e.splats) : 1.0;
    return {{"splats", e.splats},
            {"position_error_max_radii", e.position_max},
            {"position_error_mean_radii", e.position_sum / n},
            {"position_error_max_quanta", e.position_quanta_max},
            {"normal_error_max_degrees", e.normal_max_deg},
            {"normal_error_mean_degrees", e.normal_sum_deg / n},
            {"radius_growth_max", e.radius_growth_max},
            {"radius_growth_mean", e.radius_growth_sum / n},
            {"radius_shrink_max", e.radius_shrink_max},
            {"radii_raised_to_smallest_code", e.radii_raised},
            {"color_error_max", e.color_max}};
}

/// Removes the per-point sections (unless keep_points); returns their bytes.
std::uint64_t drop_points(prt::tool::PoolStep& step, bool keep_points) {
    std::uint64_t bytes = 0;
    if (!keep_points)
        for (const prt::pool::SectionType t : k_point_sections)
            if (const prt::pool::SectionEntry* e = step.input().find(t))
                bytes += e->size, step.writer().remove(t);
    return bytes;
}

/// The staged build's options agree with each other (--stage, --cells-folder, --cells).
void check_stage_options(const PointOptions& opt) {
    using prt::Error;
    if (opt.stage != "all" && opt.cells_folder.empty())
        throw Error("--stage " + opt.stage + " needs --cells-folder DIR (a folder every stage can read)");
    if (opt.stage == "all" && !opt.cells_folder.empty())
        throw Error("--cells-folder is for the staged build: give --stage plan, cells or merge");
    if ((opt.stage == "cells") != !opt.cells.empty())
        throw Error(opt.stage == "cells" ? "--stage cells needs --cells FIRST:LAST"
                                         : "--cells is for --stage cells");
    if (!opt.cells_folder.empty() && !std::filesystem::is_directory(opt.cells_folder))
        throw Error(opt.cells_folder + ": --cells-folder is not a folder");
}

/// Progress of the build from points on stderr through `progress`.
void report_to(prt::pre::PointBrickParams& p, prt::tool::StagedProgress& progress) {
    p.progress = [&progress](const char* stage, std::uint64_t done, std::uint64_t total) {
        progress.update(stage, done, total);
    };
}

/// --no-cull, --policy and --backend into the build's parameters.
void set_culling(PointOptions& opt) {
    using prt::pre::CullPolicy;
    opt.params.cull = !opt.no_cull;
    opt.params.octree.backend = opt.params.culling.backend;  // the cells' octrees where they are culled
    opt.params.culling.policy = opt.policy == "votes"    ? CullPolicy::votes
                                : opt.policy == "thesis" ? CullPolicy::thesis
                                                         : CullPolicy::greedy;
}

/// --stage cells: cells FIRST:LAST of the plan in --cells-folder; the input pool is not read (the
/// plan holds the points), so a cluster's tasks each read only their cells' records.
void cells_step(prt::tool::PoolStep& step, PointOptions& opt) {
    using namespace prt;
    pre::PointBrickParams& p = opt.params;
    set_culling(opt);
    const std::filesystem::path folder = opt.cells_folder;
    const auto [first, last] = parse_cells(opt.cells);
    pre::PointBrickStats stats;
    tool::StagedProgress progress("prt-bricks", step.quiet());
    report_to(p, progress);
    pre::build_brick_cells(folder, p, first, last, &stats);
    progress.finish();
    step.note(
        "prt-bricks: cells %u:%u: %u built, %llu stored splats, %llu after culling (%.1f s octrees, %.1f s "
        "culling, %.1f s bricks)",
        first, last, stats.cells, ull(stats.stored_splats), ull(stats.culled_splats), stats.octree_seconds,
        stats.cull_seconds, stats.brick_seconds);
    step.write_stats({{"stage", "cells"},
                      {"first", first},
                      {"last", last},
                      {"cells_built", stats.cells},
                      {"cells_culled_on_device", stats.cells_culled_on_device},
                      {"seconds", stats.seconds},
                      {"peak_rss_bytes", pre::peak_rss_bytes()}});
}

void points_step(prt::tool::PoolStep& step, PointOptions& opt, bool keep_float, bool keep_points) {
    using namespace prt;
    const pool::PoolFile& in = step.input();
    const char* tool = "prt-bricks (from points)";
    const auto positions = in.require<pool::Float3>(pool::SectionType::positions, tool);
    if (!in.has(pool::SectionType::normals))
        throw Error(step.input_path() +
                    ": no octree and no normals: run prt-import (it estimates normals) or prt-octree first");
    const auto normals = in.require<pool::Float3>(pool::SectionType::normals, tool);
    const auto colors = in.array<pool::Rgba8>(pool::SectionType::colors);
    if (keep_float)
        throw Error(step.input_path() +
                    ": --keep-float needs an octree (prt-octree); this pool has points only");
    pre::PointBrickParams& p = opt.params;
    set_culling(opt);
    p.input_mapped = in.mapped();
    p.memory = tool::memory_limit(opt.memory);
    const std::filesystem::path folder = opt.cells_folder;
    if (opt.stage != "plan") step.check_output_folder();
    OwnRadii own;  // a pool without radii: computed here (the merge reads the cells' records only)
    const bool has_radii = in.has(pool::SectionType::radii);
    const bool own_radii = !has_radii && opt.stage != "merge";
    if (own_radii)
        own = compute_own_radii(step, positions, p.threads, p.memory,
                                !opt.spill_folder.empty() ? std::filesystem::path(opt.spill_folder)
                                : opt.stage == "plan"
                                    ? folder
                                    : std::filesystem::absolute(step.output_path()).parent_path());
    p.radii_mapped = own.values.empty();  // a vector's pages would be zeroed by dropping them
    const std::span<const float> radii =
        has_radii ? in.require<float>(pool::SectionType::radii, tool) : own.radii;
    if (opt.stage == "plan") {  // no spill files: the records go to --cells-folder, and no OUTPUT
        pre::PointBrickStats stats;
        tool::StagedProgress progress("prt-bricks", step.quiet());
        report_to(p, progress);
        const std::uint32_t cells = step.about_input(
            [&] { return pre::plan_brick_cells(positions, normals, radii, colors, p, folder, &stats); });
        progress.finish();
        step.note("prt-bricks: planned %u cells of %llu points (%.2f records per point) in %s (%.1f s)",
                  cells, ull(stats.points),
                  double(stats.cell_records) / double(stats.points ? stats.points : 1), folder.c_str(),
                  stats.partition_seconds);
        step.write_stats({{"input", step.input_path()},
                          {"stage", "plan"},
                          {"cells", cells},
                          {"points", stats.points},
                          {"cell_records", stats.cell_records},
                          {"partition_seconds", stats.partition_seconds},
                          {"peak_rss_bytes", pre::peak_rss_bytes()}});
        return;
    }
    p.spill_folder = !opt.spill_folder.empty() ? std::filesystem::path(opt.spill_folder)
                                               : std::filesystem::absolute(step.output_path()).parent_path();
    step.note(
        "prt-bricks: %llu points; octree cells of at most about %llu points (--memory %s, %u cells at once), "
        "spill files in %s",
        ull(positions.size()), ull(pre::cell_capacity(p)), tool::format_bytes(p.memory).c_str(),
        pre::cell_workers(p), p.spill_folder.string().c_str());
    pre::PointBrickStats stats;
    pre::PointBricks built;
    // Lives until the pool is written: the brick payloads are copied into it then (PointBricks::data).
    tool::StagedProgress progress("prt-bricks", step.quiet());
    report_to(p, progress);
    built = opt.stage == "merge" ? pre::merge_brick_cells(folder, p, &stats) : step.about_input([&] {
        return pre::build_bricks_from_points(positions, normals, radii, colors, p, &stats);
    });
    pool::PoolWriter& writer = step.writer();
    pre::BrickedOctree& b = built.bricks;
    pre::add_brick_index_sections(std::move(b), writer);
    writer.add_generated(pool::SectionType::brick_data, 1, built.data_bytes, built.data);
    const std::uint64_t point_bytes = drop_points(step, keep_points);
    if (keep_points && own_radii)  // the per-point sections kept: the radii computed here with them
        step.writer().add_array(pool::SectionType::radii,
                                own.values.empty() ? std::vector<float>(own.radii.begin(), own.radii.end())
                                                   : std::move(own.values));
    nlohmann::json parameters = {{"brick_splats", p.bricks.brick_splats},
                                 {"lod_splats", p.bricks.lod_splats},
                                 {"direct", direct_policy_name(p.bricks.direct)},
                                 {"leaf_size", p.octree.max_leaf_splats},
                                 {"max_depth", p.octree.max_depth},
                                 {"min_cell", p.octree.min_cell_ratio},
                                 {"cull", p.cull},
                                 {"directions", p.culling.directions},
                                 {"grid", p.culling.grid},
                                 {"policy", opt.policy},
                                 {"memory", p.memory},
                                 {"keep_points", keep_points},
                                 {"staged", opt.stage == "merge"}};
    if (own_radii) parameters["radii"] = own.parameters;
    const std::uint64_t bytes = step.write(parameters);
    progress.finish();
    const double per_point = 1.0 / double(stats.points ? stats.points : 1);
    step.note(
        "prt-bricks: %u cells (deepest at level %u, at most %llu points, %.2f records per point); %llu "
        "stored splats, %llu after culling",
        stats.cells, stats.partition_depth, ull(stats.max_cell_points),
        double(stats.cell_records) * per_point, ull(stats.stored_splats), ull(stats.culled_splats));
    step.note(
        "prt-bricks: %u bricks (%u direct), top tree %u nodes (depth %u); %llu encoded splats (%.2f per "
        "point); LOD "
        "prefixes %llu nodes (%.2f B per point); pool %.2f B per point%s",
        stats.bricks.bricks, stats.bricks.direct_bricks, stats.bricks.top_nodes, stats.bricks.top_depth,
        ull(stats.bricks.encoded), double(stats.bricks.encoded) * per_point, ull(stats.bricks.lod_nodes),
        double(stats.bricks.lod_nodes * k_lod_node_bytes) * per_point, double(bytes) * per_point,
        point_bytes ? "; per-point sections dropped (--keep-points keeps them)" : "");
    const double seconds = step.seconds();
    step.note(
        "prt-bricks: %.1f s partitioning, %.1f s octrees, %.1f s culling, %.1f s bricks (%.1f s writing "
        "them), %.1f s assembly%s",
        stats.partition_seconds, stats.octree_seconds, stats.cull_seconds, stats.brick_seconds,
        stats.payload_write_seconds, stats.assemble_seconds,
        stats.cells_culled_on_device
            ? (" (" + std::to_string(stats.cells_culled_on_device) + " of " + std::to_string(stats.cells) +
               " cells culled on the GPU where they were built: their culling is in the octrees' time)")
                  .c_str()
            : "");
    if (opt.stage == "merge")  // the cells ran in other processes, perhaps at the same time
        step.note(
            "prt-bricks: staged build: the stages' times summed over their processes %.3f s (merge %.3f s), "
            "peak memory of the merge %s; wrote %s",
            stats.seconds, seconds, tool::format_bytes(pre::peak_rss_bytes()).c_str(),
            step.output_path().c_str());
    else
        step.note("prt-bricks: %.3f s building (%.2f M points/s), total %.3f s, peak memory %s; wrote %s",
                  stats.seconds, double(positions.size()) / std::max(stats.seconds, 1e-9) * 1e-6, seconds,
                  tool::format_bytes(pre::peak_rss_bytes()).c_str(), step.output_path().c_str());
    step.write_stats({{"input", step.input_path()},
                      {"parameters", parameters},
                      {"points", stats.points},
                      {"skipped_points", stats.skipped},
                      {"cells", stats.cells},
                      {"cells_culled_on_device", stats.cells_culled_on_device},
                      {"partition_depth", stats.partition_depth},
                      {"max_cell_points", stats.max_cell_points},
                      {"cell_records", stats.cell_records},
                      {"stored_splats", stats.stored_splats},
                      {"culled_splats", stats.culled_splats},
                      {"bricks", stats.bricks.bricks},
                      {"top_nodes", stats.bricks.top_nodes},
                      {"encoded_splats", stats.bricks.encoded},
                      {"direct_bricks", stats.bricks.direct_bricks},
                      {"lod_nodes", stats.bricks.lod_nodes},
                      {"lod_bytes", stats.bricks.lod_nodes * k_lod_node_bytes},
                      {"brick_data_bytes", built.data_bytes},
                      {"pool_bytes_after", bytes},
                      {"pool_bytes_per_point", double(bytes) * per_point},
                      {"codec_error", error_json(stats.bricks.error)},
                      {"build_seconds", stats.seconds},
                      {"seconds",
                       {{"partition", stats.partition_seconds},
                        {"octree", stats.octree_seconds},
                        {"cull", stats.cull_seconds},
                        {"bricks", stats.brick_seconds},
                        {"payload_writes", stats.payload_write_seconds},
                        {"assemble", stats.assemble_seconds}}},
                      {"partition_passes",
                       {{"bounds", stats.partition_pass_seconds[0]},
                        {"histogram", stats.partition_pass_seconds[1]},
                        {"count", stats.partition_pass_seconds[2]},
                        {"scatter", stats.partition_pass_seconds[3]}}},
                      {"radii", own_radii ? own.stats : nlohmann::json(nullptr)},
                      {"points_per_second", double(positions.size()) / std::max(stats.seconds, 1e-9)},
                      {"peak_rss_bytes", pre::peak_rss_bytes()},
                      {"total_seconds", seconds}});
}

void bricks_step(prt::tool::PoolStep& step, prt::pre::BrickParams params, bool keep_float, bool keep_points,
                 PointOptions& from_points) {
    using namespace prt;
    from_points.params.bricks = params;
    check_stage_options(from_points);
    if (from_points.stage == "cells") return cells_step(step, from_points);
    const pool::PoolFile& in = step.input();
    if (!pool::has_splat_octree(in)) return points_step(step, from_points, keep_float, keep_points);
    if (from_points.stage != "all")
        throw Error(
            step.input_path() + ": --stage " + from_points.stage +
            " is for the build from points; this pool has an octree (prt-bricks cuts it in one process)");
    const pool::SplatOctreeSections octree = pool::splat_octree(in, "prt-bricks");
    const std::span<const pool::Rgba8> colors = in.array<pool::Rgba8>(pool::SectionType::colors);
    if (const auto ids = in.array<std::uint32_t>(pool::SectionType::material_ids); !ids.empty()) {
        std::set<std::uint32_t> distinct(ids.begin(), ids.end());
        step.note("prt-bricks: material_ids (%zu distinct) are not carried into bricks", distinct.size());
    }
    step.check_output_folder();
    step.note("prt-bricks: %llu stored splats in %u nodes, at most %u splats per brick",
              ull(octree.splats.size()), octree.info.node_count, params.brick_splats);
    pre::BrickStats stats;
    pre::BrickedOctree bricked;
    {
        tool::StagedProgress progress("prt-bricks", step.quiet());
        params.progress = [&](std::uint64_t done, std::uint64_t total) {
            progress.update("encoding bricks", done, total);
        };
        bricked = step.about_input([&] { return pre::build_bricks(octree, colors, params, &stats); });
        progress.finish();
    }
    if (keep_float) bricked.info.flags |= pool::k_bricks_float_kept;
    pool::PoolWriter& writer = step.writer();
    pre::add_brick_sections(std::move(bricked), writer);
    if (!keep_float)
        for (const pool::SectionType t : {pool::SectionType::octree_info, pool::SectionType::octree_nodes,
                                          pool::SectionType::leaf_info, pool::SectionType::splats})
            writer.remove(t);
    const std::uint64_t point_bytes = drop_points(step, keep_points);
    const nlohmann::json parameters = {{"brick_splats", params.brick_splats},
                                       {"lod_splats", params.lod_splats},
                                       {"direct", direct_policy_name(params.direct)},
                                       {"keep_float", keep_float},
                                       {"keep_points", keep_points}};
    const std::uint64_t bytes = step.write(parameters);

    const pre::CodecError& e = stats.error;
    const double n = e.splats ? double(e.splats) : 1.0;
    const double mib = 1.0 / (1024.0 * 1024.0);
    const std::uint64_t points = octree.info.unique_splats;
    const double per_point = 1.0 / double(points ? points : 1);
    step.note(
        "prt-bricks: %u bricks (%u to %u splat references; %u direct), top tree %u nodes (depth %u); %llu "
        "references to %llu encoded splats (%.2f and %.2f per point); LOD prefixes %llu nodes (%.2f B per "
        "point)",
        stats.bricks, stats.min_brick_splats, stats.max_brick_splats, stats.direct_bricks, stats.top_nodes,
        stats.top_depth, ull(stats.splats), ull(stats.encoded), double(stats.splats) * per_point,
        double(stats.encoded) * per_point, ull(stats.lod_nodes),
        double(stats.lod_nodes * k_lod_node_bytes) * per_point);
    step.note(
        "prt-bricks: splats %.1f -> %.1f MiB (%.2f B per point with nodes, leaf ranges and references); "
        "pool %.1f -> %.1f MiB (%.2f B per point)%s",
        double(octree.splats.size_bytes() + octree.leaf_info.size_bytes() + octree.nodes.size_bytes()) * mib,
        double(stats.data_bytes) * mib, double(stats.data_bytes) * per_point, double(in.file_size()) * mib,
        double(bytes) * mib, double(bytes) * per_point,
        point_bytes ? (", per-point sections dropped (" + std::to_string(point_bytes / 1048576) +
                       " MiB; --keep-points keeps them)")
                          .c_str()
                    : "");
    step.note(
        "prt-bricks: codec error: position max %.4f mean %.4f splat radii (max %.3f quanta), normal max %.3f "
        "mean %.3f deg, radius growth max %.4f mean %.4f (%llu raised to the smallest code), colour max %u",
        e.position_max, e.position_sum / n, e.position_quanta_max, e.normal_max_deg, e.normal_sum_deg / n,
        e.radius_growth_max, e.radius_growth_sum / n, ull(e.radii_raised), e.color_max);
    step.note("prt-bricks: %.3f s building, total %.3f s; wrote %s", stats.seconds, step.seconds(),
              step.output_path().c_str());
    step.write_stats({{"input", step.input_path()},
                      {"parameters", parameters},
                      {"bricks", stats.bricks},
                      {"top_nodes", stats.top_nodes},
                      {"top_depth", stats.top_depth},
                      {"min_brick_splats", stats.min_brick_splats},
                      {"max_brick_splats", stats.max_brick_splats},
                      {"splats", stats.splats},
                      {"encoded_splats", stats.encoded},
                      {"direct_bricks", stats.direct_bricks},
                      {"lod_nodes", stats.lod_nodes},
                      {"lod_bytes", stats.lod_nodes * k_lod_node_bytes},
                      {"points", points},
                      {"point_section_bytes_dropped", point_bytes},
                      {"pool_bytes_per_point", double(bytes) * per_point},
                      {"float_octree_bytes", octree.splats.size_bytes() + octree.leaf_info.size_bytes() +
                                                 octree.nodes.size_bytes()},
                      {"brick_data_bytes", stats.data_bytes},
                      {"bytes_per_splat", double(stats.data_bytes) / n},
                      {"brick_bytes_per_point", double(stats.data_bytes) * per_point},
                      {"pool_bytes_before", in.file_size()},
                      {"pool_bytes_after", bytes},
                      {"codec_error", error_json(e)},
                      {"build_seconds", stats.seconds},
                      {"total_seconds", step.seconds()}});
}

}  // namespace

int main(int argc, char** argv) {
    prt::pre::BrickParams params;
    bool keep_float = false, keep_points = false;
    std::string direct_word = "smaller";
    PointOptions points;
    prt::tool::PoolStep step(
        "prt-bricks", k_description,
        {.input = "Input pool file with a splat octree (prt-octree, prt-cull), or with points and radii "
                  "(prt-radii)",
         .output =
             "Output pool file (written atomically; may equal INPUT); required except with --stage plan "
             "or cells, which write only into --cells-folder (a -o given there is ignored, with a "
             "note) [none]"});
    return step.run(
        argc, argv,
        [&](CLI::App& app) {
            // --stage plan and cells write the plan and the parts into --cells-folder, never OUTPUT
            // (plan's records go there too, not to spill files beside OUTPUT): -o is optional there.
            step.input_unused_when([&points]() -> std::string {
                return points.stage == "cells" ? "--stage cells reads only --cells-folder" : "";
            });
            step.output_unused_when([&points]() -> std::string {
                if (points.stage == "plan")
                    return "--stage plan writes plan.bin and records.bin into --cells-folder";
                if (points.stage == "cells") return "--stage cells writes its part into --cells-folder";
                return {};
            });
            app.add_option(
                   "--brick-splats", params.brick_splats,
                   "N: a node whose subtree holds at most N stored splats (replicas counted) becomes a "
                   "brick")
                ->check(CLI::Range(1u, 0xFFFFFFFFu))
                ->capture_default_str();
            app.add_option("--lod-splats", params.lod_splats,
                           "M: each brick's level-of-detail prefix (sections brick_lod, lod_nodes) holds its "
                           "top levels down to the deepest whose non-empty nodes hold >= M splat references "
                           "on average, a compressed disc per node; rays stop at a node below a pixel "
                           "(prt-play --lod-pixels). Resident when streaming if the budget holds them, else "
                           "streamed ahead of the bricks: a scan streamed under a small budget converges "
                           "with deeper prefixes (12: about 2 bytes a point against 0.5 at 32). 0: no prefix")
                ->capture_default_str();
            app.add_option("--direct", direct_word,
                           "Direct bricks: a brick stores its leaves' splats in leaf order, a replica once "
                           "per leaf, with no references (one read per splat test instead of two): "
                           "'smaller' where that takes no more bytes (little replication, as in culled "
                           "pools), 'always', 'never'")
                ->check(CLI::IsMember({"smaller", "always", "never"}))
                ->capture_default_str();
            app.add_flag(
                "--keep-float", keep_float,
                "Keep the float octree sections (octree_info, octree_nodes, leaf_info, splats) beside "
                "the bricks (default: removed)");
            app.add_flag("--keep-points", keep_points,
                         "Keep the per-point sections (positions, normals, colors, radii, material_ids, "
                         "intensities, scan_ids) beside the bricks, for tools that read points (default: "
                         "removed)");
            prt::pre::PointBrickParams& pp = points.params;
            const char* from_points = "From points (an input without an octree)";
            app.add_option("-X,--leaf-size", pp.octree.max_leaf_splats,
                           "prt-octree's X (thesis 3.2): a node overlapped by more splats is split")
                ->check(CLI::Range(1u, 1u << 20))
                ->capture_default_str()
                ->group(from_points);
            app.add_option("--max-depth", pp.octree.max_depth, "prt-octree's maximum depth (root = 0)")
                ->check(CLI::Range(0u, 30u))
                ->capture_default_str()
                ->group(from_points);
            app.add_option(
                   "--min-cell", pp.octree.min_cell_ratio,
                   "prt-octree's --min-cell: do not split a node whose edge is below this times the mean "
                   "radius of its splats (0 = off)")
                ->check(CLI::Range(0.0f, 1.0e6f))
                ->capture_default_str()
                ->group(from_points);
            app.add_flag("--no-cull", points.no_cull,
                         "Keep every replica (default: probe-ray culling as prt-cull, thesis 3.4)")
                ->group(from_points);
            app.add_option("--directions", pp.culling.directions, "prt-cull's probe directions per leaf")
                ->check(CLI::Range(1u, 256u))
                ->capture_default_str()
                ->group(from_points);
            app.add_option("--grid", pp.culling.grid, "prt-cull's G x G probe lines per direction")
                ->check(CLI::Range(1u, 64u))
                ->capture_default_str()
                ->group(from_points);
            app.add_option("--policy", points.policy, "prt-cull's policy: greedy, votes or thesis")
                ->check(CLI::IsMember({"greedy", "votes", "thesis"}))
                ->capture_default_str()
                ->group(from_points);
            app.add_option(
                   "--backend", pp.culling.backend,
                   "Where the cells' octrees are built and culled: auto (CUDA when a device is usable, else "
                   "CPU), cpu or cuda (the same bricks either way)")
                ->check(CLI::IsMember({"auto", "cpu", "cuda"}))
                ->capture_default_str()
                ->group(from_points);
            app.add_option(
                   "--cell-workers", pp.cell_workers,
                   "Octree cells built at the same time, each with -j / N threads; --memory is shared "
                   "among them. 0: one per thread (the result is the same for any N)")
                ->capture_default_str()
                ->group(from_points);
            prt::tool::PoolStep::add_memory(
                app, points.memory,
                "Memory for the octree cells' builds (SIZE, e.g. 8G); larger models are split into cells of "
                "about SIZE / (840 x cell workers) points (default: half the physical memory)")
                ->group(from_points);
            app.add_option(
                   "--spill-folder", points.spill_folder,
                   "Folder of the spill files of --stage all and merge (removed as soon as created; about "
                   "32 bytes per point and the brick payloads twice) (default: the output's folder)")
                ->group(from_points);
            const char* staged = "Staged build (one model's cells on several processes or machines)";
            app.add_option(
                   "--stage", points.stage,
                   "all: the whole build from points here; plan: partition the points into octree "
                   "cells and write the plan and the cells' points into --cells-folder (--stats-json "
                   "gets the number of cells); cells: build cells --cells FIRST:LAST of the plan into a "
                   "part file there (INPUT is not read); merge: assemble the parts into OUTPUT. Every "
                   "stage takes the same options; the result equals --stage all byte for byte "
                   "(scripts/prt-bricks-dask runs the stages on a Dask cluster); -o is needed by all and "
                   "merge only (plan and cells ignore it)")
                ->check(CLI::IsMember({"all", "plan", "cells", "merge"}))
                ->capture_default_str()
                ->group(staged);
            app.add_option(
                   "--cells-folder", points.cells_folder,
                   "The staged build's folder, shared by every stage (plan.bin, records.bin: 32 B per "
                   "point and cell it reaches; cells-FIRST-LAST.bin: the parts) [none]")
                ->group(staged);
            app.add_option("--cells", points.cells,
                           "--stage cells: the cells FIRST:LAST to build (FIRST to LAST - 1) [none]")
                ->group(staged);
            app.add_option("--cell-points", pp.cell_points,
                           "Testing: cells of at most about this many points whatever --memory")
                ->group("");
            prt::tool::PoolStep::add_threads(app, params.threads);
        },
        [&](prt::tool::PoolStep& s) {
            points.params.threads = params.threads;
            params.direct = k_direct_words.at(direct_word);
            bricks_step(s, params, keep_float, keep_points, points);
        });
}
