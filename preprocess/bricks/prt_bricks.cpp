// prt-bricks: cuts the splat octree into bricks of compressed splats with a level-of-detail disc per
// top node (issue 17; format in formats/POOL.md, "Bricks and level of detail").
#include <cstdio>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "brick_build.h"
#include "prt/formats/octree_sections.h"
#include "prt/pool_step.h"

namespace {

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
    "intensities are not carried into bricks. Reports the codec's error against the float splats.";

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

void bricks_step(prt::tool::PoolStep& step, prt::pre::BrickParams params, bool keep_float, bool keep_points) {
    using namespace prt;
    const pool::PoolFile& in = step.input();
    if (!pool::has_splat_octree(in)) throw Error(step.input_path() + ": no octree: run prt-octree first");
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
    std::uint64_t point_bytes = 0;
    if (!keep_points)
        for (const pool::SectionType t : k_point_sections)
            if (const pool::SectionEntry* e = in.find(t)) point_bytes += e->size, writer.remove(t);
    const nlohmann::json parameters = {
        {"brick_splats", params.brick_splats}, {"keep_float", keep_float}, {"keep_points", keep_points}};
    const std::uint64_t bytes = step.write(parameters);

    const pre::CodecError& e = stats.error;
    const double n = e.splats ? double(e.splats) : 1.0;
    const double mib = 1.0 / (1024.0 * 1024.0);
    const std::uint64_t points = octree.info.unique_splats;
    const double per_point = 1.0 / double(points ? points : 1);
    step.note(
        "prt-bricks: %u bricks (%u to %u splat references), top tree %u nodes (depth %u); %llu references "
        "to %llu encoded splats (%.2f and %.2f per point)",
        stats.bricks, stats.min_brick_splats, stats.max_brick_splats, stats.top_nodes, stats.top_depth,
        ull(stats.splats), ull(stats.encoded), double(stats.splats) * per_point,
        double(stats.encoded) * per_point);
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
    prt::tool::PoolStep step("prt-bricks", k_description,
                             {.input = "Input pool file with a splat octree (prt-octree, prt-cull)"});
    return step.run(
        argc, argv,
        [&](CLI::App& app) {
            app.add_option(
                   "--brick-splats", params.brick_splats,
                   "N: a node whose subtree holds at most N stored splats (replicas counted) becomes a "
                   "brick")
                ->check(CLI::Range(1u, 0xFFFFFFFFu))
                ->capture_default_str();
            app.add_flag(
                "--keep-float", keep_float,
                "Keep the float octree sections (octree_info, octree_nodes, leaf_info, splats) beside "
                "the bricks (default: removed)");
            app.add_flag("--keep-points", keep_points,
                         "Keep the per-point sections (positions, normals, colors, radii, material_ids, "
                         "intensities, scan_ids) beside the bricks, for tools that read points (default: "
                         "removed)");
            prt::tool::PoolStep::add_threads(app, params.threads);
        },
        [&](prt::tool::PoolStep& s) { bricks_step(s, params, keep_float, keep_points); });
}
