// prt-octree: the adaptive splat octree in the GPU layout of thesis 2.2 / 3.2, with splats replicated
// into every leaf their disk overlaps (thesis 3.4).
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "octree_build.h"
#include "prt/formats/pool.h"
#include "prt/tool.h"

int main(int argc, char** argv) {
    std::string input, output;
    prt::pre::OctreeParams params;
    bool no_replicate = false;
    std::string split_by = "overlaps";
    std::string stats_json;
    return prt::tool::run(
        argc, argv, "prt-octree",
        "Splat octree (thesis 2.2, 3.2, 3.4): an adaptive octree over the splats of INPUT (positions, "
        "normals "
        "and radii: run prt-radii first). A node is split while more than X splats overlap it (replicas "
        "included; --split-by centres counts centres only), up to --max-depth, unless its edge is below "
        "--min-cell times the mean radius of those "
        "splats. Every splat is stored in every leaf its disk overlaps (exact disk/box test) unless "
        "--no-replicate. Nodes: 32-bit (2-bit type, 30-bit address), 8 children together in Morton order, "
        "breadth first. Writes OUTPUT with the sections octree_info, octree_nodes, leaf_info and splats; "
        "the other sections are carried over.",
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("input", input, "Input pool file (with radii)")->required();
            app.add_option("-o,--output", output, "Output pool file (written atomically; may equal INPUT)")
                ->required();
            app.add_option("-X,--leaf-size", params.max_leaf_splats,
                           "X of thesis 3.2: a node overlapped by more splats is split")
                ->check(CLI::Range(1u, 1u << 20));
            app.add_option("--max-depth", params.max_depth,
                           "Maximum depth (root = 0); leaves there are never split")
                ->check(CLI::Range(0u, 30u));
            app.add_option("--min-cell", params.min_cell_ratio,
                           "Do not split a node whose edge is below this times the mean radius of its splats "
                           "(0 = off)")
                ->check(CLI::Range(0.0f, 1.0e6f));
            app.add_option("--split-by", split_by,
                           "What is compared with X: 'overlaps' (every splat overlapping the node, replicas "
                           "included: X bounds the splats per leaf) or 'centres' (splat centres in the node, "
                           "thesis 3.2 after [LMR07]; leaves then hold more than X splats)")
                ->check(CLI::IsMember({"overlaps", "centres"}));
            app.add_flag(
                "--no-replicate", no_replicate,
                "Store each splat once, in the leaf holding its centre (counts centres, not overlaps)");
            app.add_option("-j,--threads", params.threads, "Worker threads (0 = all hardware threads)");
            app.add_option("--stats-json", stats_json,
                           "Also write the statistics as JSON to this file (benchmarks)");
        },
        [&](const prt::tool::CommonOptions& common) {
            using namespace prt;
            params.replicate = !no_replicate;
            params.split_by_centres = split_by == "centres";
            const double start = tool::now_seconds();
            const pool::PoolFile in = pool::PoolFile::open(input);
            const auto positions = in.require<pool::Float3>(pool::SectionType::positions, "prt-octree");
            if (!in.has(pool::SectionType::radii))
                throw Error(input + ": no radii section: run prt-radii first");
            if (!in.has(pool::SectionType::normals))
                throw Error(input + ": no normals section: splats need normals (prt-import estimates them)");
            const auto normals = in.array<pool::Float3>(pool::SectionType::normals);
            const auto radii = in.array<float>(pool::SectionType::radii);

            tool::note(common.quiet, "prt-octree: %zu splats (X = %u %s, max depth %u, %s)", positions.size(),
                       params.max_leaf_splats, split_by.c_str(), params.max_depth,
                       params.replicate ? "replicated" : "not replicated");
            pre::OctreeStats stats;
            pre::SplatOctree octree;
            {
                tool::Progress progress("prt-octree: building", positions.size(), common.quiet);
                params.progress = [&](std::uint64_t done, std::uint64_t total) {
                    progress.update(total ? done * positions.size() / total : 0);
                };
                try {
                    octree = pre::build_octree(positions, normals, radii, params, &stats);
                } catch (const Error& e) {
                    throw Error(input + ": " + e.what());
                }
                progress.finish();
            }

            pool::PoolWriter writer;
            writer.carry_over(in);
            pre::add_octree_sections(std::move(octree), writer);
            const nlohmann::json parameters = {{"leaf_size", params.max_leaf_splats},
                                               {"max_depth", params.max_depth},
                                               {"min_cell", params.min_cell_ratio},
                                               {"replicate", params.replicate},
                                               {"split_by", split_by}};
            writer.add_provenance("prt-octree", PRT_VERSION, parameters.dump());
            const std::uint64_t bytes = writer.write(output);

            const double n = double(positions.size());
            const double total_seconds = tool::now_seconds() - start;
            if (!stats_json.empty()) {
                const nlohmann::json j = {{"tool", "prt-octree"},
                                          {"points", positions.size()},
                                          {"parameters", parameters},
                                          {"nodes", stats.nodes},
                                          {"depth", stats.depth},
                                          {"filled_leaves", stats.filled_leaves},
                                          {"empty_leaves", stats.empty_leaves},
                                          {"max_leaf_splats", stats.max_leaf_count},
                                          {"unique_splats", stats.unique_splats},
                                          {"stored_splats", stats.stored_splats},
                                          {"skipped_splats", stats.skipped_splats},
                                          {"replication_factor", stats.replication_factor},
                                          {"octree_bytes_per_point", double(stats.bytes) / n},
                                          {"pool_bytes_per_point", double(bytes) / n},
                                          {"build_seconds", stats.seconds},
                                          {"total_seconds", total_seconds}};
                std::ofstream out(stats_json);
                out << j.dump(2) << "\n";
                if (!out) throw Error(stats_json + ": cannot write the statistics");
            }
            tool::note(
                common.quiet,
                "prt-octree: %u nodes, depth %u, %u filled + %u empty leaves, at most %llu splats in a leaf",
                stats.nodes, stats.depth, stats.filled_leaves, stats.empty_leaves,
                static_cast<unsigned long long>(stats.max_leaf_count));
            tool::note(common.quiet,
                       "prt-octree: %llu splats stored for %llu unique: replication factor %.3f",
                       static_cast<unsigned long long>(stats.stored_splats),
                       static_cast<unsigned long long>(stats.unique_splats), stats.replication_factor);
            if (stats.skipped_splats > 0)
                tool::note(common.quiet,
                           "prt-octree: skipped %llu points without a finite positive radius or a normal",
                           static_cast<unsigned long long>(stats.skipped_splats));
            tool::note(common.quiet,
                       "prt-octree: octree %.1f bytes per input point, pool %.1f bytes per input point; "
                       "build %.3f s, "
                       "total %.3f s; wrote %s",
                       double(stats.bytes) / n, double(bytes) / n, stats.seconds, total_seconds,
                       output.c_str());
        });
}
