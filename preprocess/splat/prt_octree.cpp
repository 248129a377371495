// prt-octree: the adaptive splat octree in the GPU layout of thesis 2.2 / 3.2, with splats replicated
// into every leaf their disk overlaps (thesis 3.4).
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "octree_build.h"
#include "prt/pool_step.h"

namespace {

constexpr const char* k_description =
    "Splat octree (thesis 2.2, 3.2, 3.4): an adaptive octree over the splats of INPUT (positions, "
    "normals "
    "and radii: run prt-radii first). A node is split while more than X splats overlap it (replicas "
    "included; --split-by centres counts centres only), up to --max-depth, unless its edge is below "
    "--min-cell times the mean radius of those "
    "splats. Every splat is stored in every leaf its disk overlaps (exact disk/box test) unless "
    "--no-replicate. Nodes: 32-bit (2-bit type, 30-bit address), 8 children together in Morton order, "
    "breadth first. Writes OUTPUT with the sections octree_info, octree_nodes, leaf_info and splats; "
    "the other sections are carried over.";

void report(const prt::tool::PoolStep& step, const prt::pre::OctreeStats& stats, double n,
            std::uint64_t bytes) {
    step.note("prt-octree: %u nodes, depth %u, %u filled + %u empty leaves, at most %llu splats in a leaf",
              stats.nodes, stats.depth, stats.filled_leaves, stats.empty_leaves,
              static_cast<unsigned long long>(stats.max_leaf_count));
    step.note("prt-octree: %llu splats stored for %llu unique: replication factor %.3f",
              static_cast<unsigned long long>(stats.stored_splats),
              static_cast<unsigned long long>(stats.unique_splats), stats.replication_factor);
    if (stats.skipped_splats > 0)
        step.note("prt-octree: skipped %llu points without a finite positive radius or a normal",
                  static_cast<unsigned long long>(stats.skipped_splats));
    step.note(
        "prt-octree: octree %.1f bytes per input point, pool %.1f bytes per input point; build %.3f s, "
        "total %.3f s; wrote %s",
        double(stats.bytes) / n, double(bytes) / n, stats.seconds, step.seconds(),
        step.output_path().c_str());
}

void octree_step(prt::tool::PoolStep& step, prt::pre::OctreeParams params, bool no_replicate,
                 const std::string& split_by) {
    using namespace prt;
    params.replicate = !no_replicate;
    params.split_by_centres = split_by == "centres";
    const pool::PoolFile& in = step.input();
    const auto positions = in.require<pool::Float3>(pool::SectionType::positions, "prt-octree");
    if (!in.has(pool::SectionType::radii))
        throw Error(step.input_path() + ": no radii section: run prt-radii first");
    if (!in.has(pool::SectionType::normals))
        throw Error(step.input_path() +
                    ": no normals section: splats need normals (prt-import estimates them)");
    const auto normals = in.array<pool::Float3>(pool::SectionType::normals);
    const auto radii = in.array<float>(pool::SectionType::radii);

    params.backend = pre::resolve_octree_backend(params.backend);
    step.note("prt-octree: %zu splats (X = %u %s, max depth %u, %s, %s)", positions.size(),
              params.max_leaf_splats, split_by.c_str(), params.max_depth,
              params.replicate ? "replicated" : "not replicated", params.backend.c_str());
    pre::OctreeStats stats;
    pre::SplatOctree octree;
    {
        tool::Progress progress("prt-octree: building", positions.size(), step.quiet());
        params.progress = [&](std::uint64_t done, std::uint64_t total) {
            progress.update(total ? done * positions.size() / total : 0);
        };
        octree =
            step.about_input([&] { return pre::build_octree(positions, normals, radii, params, &stats); });
        progress.finish();
    }

    pre::add_octree_sections(std::move(octree), step.writer());
    const nlohmann::json parameters = {{"leaf_size", params.max_leaf_splats},
                                       {"max_depth", params.max_depth},
                                       {"min_cell", params.min_cell_ratio},
                                       {"replicate", params.replicate},
                                       {"split_by", split_by}};
    const std::uint64_t bytes = step.write(parameters);

    const double n = double(positions.size());
    step.write_stats({{"points", positions.size()},
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
                      {"total_seconds", step.seconds()}});
    report(step, stats, n, bytes);
}

}  // namespace

int main(int argc, char** argv) {
    prt::pre::OctreeParams params;
    bool no_replicate = false;
    std::string split_by = "overlaps";
    prt::tool::PoolStep step("prt-octree", k_description,
                             {.input = "Input pool file (with radii)",
                              .stats = "Also write the statistics as JSON to this file (benchmarks)"});
    return step.run(
        argc, argv,
        [&](CLI::App& app) {
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
            app.add_option(
                   "--backend", params.backend,
                   "Where the tree is built: cpu, cuda (level by level on the GPU) or auto (CUDA when "
                   "a device is usable); the same octree either way")
                ->check(CLI::IsMember({"auto", "cpu", "cuda"}))
                ->capture_default_str();
            prt::tool::PoolStep::add_threads(app, params.threads);
        },
        [&](prt::tool::PoolStep& s) { octree_step(s, params, no_replicate, split_by); });
}
