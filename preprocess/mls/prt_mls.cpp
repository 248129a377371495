// prt-mls: the kd-tree for ray tracing the exact MLS surface (Wald & Seidel 2005, 3.4).
#include <nlohmann/json.hpp>
#include <string>

#include "mls_build.h"
#include "mls_pool.h"
#include "prt/pool_step.h"

namespace prt::mls {

// --stats-json: the statistics whose keys are their member names; stats_json() adds the others.
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(BuildStats, points, skipped, splats, nodes, leaves, empty_leaves, refs,
                                   depth, sah_leaves, sah_cost, shrunk_leaves, culled_leaves, shrink_splits,
                                   refs_removed, volume_before, volume_after, interval_boxes, collapsed,
                                   bvh_nodes, bvh_depth, seconds_sah, seconds_shrink, seconds_bvh)

}  // namespace prt::mls

namespace {

constexpr const char* k_description =
    R"(Build the kd-tree for ray tracing the exact MLS point-set surface of Wald & Seidel 2005 (the
accuracy reference of PointRT) and add it to the pool.

The surface is Adamson and Alexa's implicit surface: with w_i(x) = max(0, 1 - |x - p_i| / R_i),
  F(x) = (sum w_i (x - p_i)) . (sum w_i n_i) = 0,
where p_i, n_i are the points and normals and R_i = --support-factor x the splat radius (prt-radii:
the distance to the k-th nearest neighbour). Points with no usable radius or normal are skipped.

The kd-tree (WS05 3.4): SAH splits over each splat's support box, every cell referencing the splats
whose support reaches it; with --encourage, encouraged splits for small cells (3.4.2: the SAH's cell
cost C_isec n becomes C_isec n E(n), E(n) = min(1, (95 + 5 n 21 / L) / 200), L = --encourage-limit;
L = 21 is WS05's; off by default: the finer shrinking makes larger cells as tight, and the GPU walk
pays per node);
cell shrinking (3.4.1): each leaf is cut into --slices slices per axis and slices at both ends that
provably hold no surface are cut off (interval arithmetic, so no surface is ever lost), a leaf with
none left becomes empty; post-collapse (3.4.3) of splits whose two children are empty. Then (not in
WS05) a BVH over the non-empty leaves, each boxed by its cell cut to its splats' supports: rays walk
it instead of the kd-tree and skip the empty cells (same cells sampled, same hits; --no-bvh: the
kd-tree alone, as before 2026-12-03).

INPUT needs positions, normals and radii (prt-import, prt-radii); the other sections are carried
over, an earlier MLS tree is replaced.)";

using ull = unsigned long long;

void report(const prt::tool::PoolStep& step, const prt::mls::BuildOptions& opt,
            const prt::mls::BuildStats& st) {
    if (st.skipped > 0)
        step.note("prt-mls: skipped %llu of %llu points (no usable radius, normal or position)",
                  ull(st.skipped), ull(st.points));
    step.note(
        "prt-mls: %llu splats; kd-tree %llu nodes, depth %u, %llu leaves (%llu empty), %.1f refs per "
        "non-empty leaf, %.2f refs per splat",
        ull(st.splats), ull(st.nodes), st.depth, ull(st.leaves), ull(st.empty_leaves),
        st.mean_refs_per_leaf(), st.splats ? double(st.refs) / double(st.splats) : 0.0);
    step.note("prt-mls: SAH: %llu leaves, cost %.2f, %.2f s", ull(st.sah_leaves), st.sah_cost,
              st.seconds_sah);
    if (opt.shrink)
        step.note(
            "prt-mls: shrinking: %llu leaves shrunk, %llu emptied, %llu splits inserted, %llu refs "
            "dropped, leaf volume %.1f%% of before, %llu interval boxes, %.2f s",
            ull(st.shrunk_leaves), ull(st.culled_leaves), ull(st.shrink_splits), ull(st.refs_removed),
            st.volume_before > 0 ? 100.0 * st.volume_after / st.volume_before : 0.0, ull(st.interval_boxes),
            st.seconds_shrink);
    if (opt.collapse) step.note("prt-mls: post-collapse removed %llu splits", ull(st.collapsed));
    if (opt.bvh)
        step.note("prt-mls: BVH over the non-empty leaves: %llu nodes, depth %u, %.2f s", ull(st.bvh_nodes),
                  st.bvh_depth, st.seconds_bvh);
}

nlohmann::json stats_json(const prt::mls::BuildStats& st) {
    nlohmann::json j = st;
    j["refs_per_leaf"] = st.mean_refs_per_leaf();
    j["seconds_build"] = st.seconds_total;
    return j;
}

void mls_step(prt::tool::PoolStep& step, prt::mls::BuildOptions opt) {
    using namespace prt;
    const pool::PoolFile& in = step.input();
    const auto positions = in.require<pool::Float3>(pool::SectionType::positions, "prt-mls");
    const auto normals =
        in.require<pool::Float3>(pool::SectionType::normals, "prt-mls (run prt-import with normals)");
    const auto radii = in.require<float>(pool::SectionType::radii, "prt-mls (run prt-radii)");

    // The leaf count, hence the progress total, is known once the SAH pass is done.
    tool::StagedProgress progress("prt-mls", step.quiet());
    mls::MlsModel model = step.about_input([&] {
        return mls::build_mls(positions, normals, radii, opt, [&](std::uint64_t done, std::uint64_t total) {
            progress.update("shrinking leaves", done, total);
        });
    });
    progress.finish();
    const mls::BuildStats st = model.stats;
    report(step, opt, st);

    const nlohmann::json parameters = {{"support_factor", opt.support_factor},
                                       {"samples", opt.samples},
                                       {"cost_traversal", opt.cost_traversal},
                                       {"cost_intersection", opt.cost_intersection},
                                       {"shrink", opt.shrink},
                                       {"slices", opt.shrink_slices},
                                       {"shrink_axes", opt.shrink_axes},
                                       {"shrink_depth", opt.shrink_depth},
                                       {"encourage", opt.encourage},
                                       {"encourage_limit", opt.encourage_limit},
                                       {"collapse", opt.collapse},
                                       {"bvh", opt.bvh},
                                       {"max_depth", opt.max_depth}};
    mls::write_mls_sections(std::move(model), step.writer());
    const std::uint64_t bytes = step.write(parameters);
    const double total = step.seconds();
    step.note("prt-mls: wrote %s: %.2f MB (%.1f bytes per point) in %.2f s", step.output_path().c_str(),
              double(bytes) / 1e6, st.points ? double(bytes) / double(st.points) : 0.0, total);

    nlohmann::json j = stats_json(st);
    j["parameters"] = parameters;
    j["seconds_total"] = total;
    j["bytes"] = bytes;
    step.write_stats(std::move(j));
}

}  // namespace

int main(int argc, char** argv) {
    prt::mls::BuildOptions opt;
    bool no_shrink = false, no_collapse = false, no_bvh = false;
    prt::tool::PoolStep step("prt-mls", k_description,
                             {.input = "Input pool (positions, normals, radii)",
                              .output = "Output pool (written atomically; may equal INPUT)",
                              .stats = "Also write the build statistics as JSON to this file"});
    return step.run(
        argc, argv,
        [&](CLI::App& app) {
            app.add_option("--support-factor", opt.support_factor,
                           "MLS support radius R_i as a multiple of the splat radius r_i")
                ->check(CLI::Range(1e-3f, 1e3f));
            app.add_option("--samples", opt.samples,
                           "Samples per cell interval the tree is built for (WS05 3.2.2's k; recorded, the "
                           "renderer may override)")
                ->check(CLI::Range(2u, 1024u));
            app.add_option("--cost-traversal", opt.cost_traversal, "SAH C_trav (WS05 eq. 3)")
                ->check(CLI::PositiveNumber);
            app.add_option("--cost-intersection", opt.cost_intersection,
                           "SAH C_isec per referenced splat (WS05 eq. 3)")
                ->check(CLI::PositiveNumber);
            app.add_option("--encourage-limit", opt.encourage_limit,
                           "Encouraged splits: refs per cell where E(n) reaches 1 (WS05: 21)")
                ->check(CLI::Range(1.0f, 1e6f));
            app.add_flag("--no-shrink", no_shrink, "Skip cell shrinking (WS05 3.4.1)");
            app.add_flag("--encourage,!--no-encourage", opt.encourage,
                         "Encouraged splits for small cells, E(n) (WS05 3.4.2); default: plain SAH cost");
            app.add_flag("--no-collapse", no_collapse, "Skip the post-collapse of empty splits (WS05 3.4.3)");
            app.add_flag("--no-bvh", no_bvh,
                         "Write no BVH over the non-empty leaves: rays walk the kd-tree and its empty cells "
                         "(same hits, slower)");
            app.add_option(
                   "--slices", opt.shrink_slices,
                   "Shrinking: slices per axis (WS05 uses 7-13; more cut cells closer to the surface)")
                ->check(CLI::Range(2u, 256u));
            app.add_option(
                   "--shrink-axes", opt.shrink_axes,
                   "Shrinking: 1 = the dominant normal axis only (WS05), 3 = every axis, dominant first")
                ->check(CLI::IsMember({1u, 3u}));
            app.add_option("--shrink-depth", opt.shrink_depth,
                           "Shrinking: halvings of a slice before an unresolved piece keeps it")
                ->check(CLI::Range(0u, 16u));
            app.add_option("--max-depth", opt.max_depth, "Deepest SAH level")->check(CLI::Range(1u, 58u));
            prt::tool::PoolStep::add_threads(app, opt.threads);
        },
        [&](prt::tool::PoolStep& s) {
            opt.shrink = !no_shrink;
            opt.collapse = !no_collapse;
            opt.bvh = !no_bvh;
            prt::mls::validate(opt);
            mls_step(s, opt);
        });
}
