// prt-iso: the Implicit Surface Octree of thesis ch. 4 from a pool's points and normals.
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "iso_build.h"
#include "iso_pool.h"
#include "prt/formats/pool.h"
#include "prt/formats/scene.h"
#include "prt/tool.h"

namespace {

constexpr const char* k_description =
    R"(Implicit Surface Octree (thesis ch. 4): an octree over the points of INPUT whose filled leaves
store, at their 8 corners, the isovalue f(Q) = (Q - p(Q)) . n(Q) with p, n the Gaussian-weighted
means of the nearby points' positions and normals (eq. 4.1-4.3; sigma_i = smoothing x radius of
influence r_i), the weighted normal and the weighted color. The renderer interpolates them
trilinearly inside each leaf and finds f = 0 along the ray.

Radii of influence: the radii section (prt-radii) or, without one, the distance to the k-th nearest
neighbour computed here (the same rule as prt-radii, outliers clamped). Leaves: a node holding
points is split while above --min-level, or while it holds more than --max-points points and is
above --max-level (level of detail, thesis 4.6). Empty leaves touched by a point's influence disk
become passive leaves (4.3.1); filled leaves next to leaves more than one level finer are split
(2:1 balance, 4.5.1); where a leaf's face has corners of both signs the surface goes on behind it,
and the leaves there are filled too (surface closure); leaves whose corners all share one sign
hold no surface and are dropped. No surface where there is no data (issue 15): a leaf holds surface
only when every corner projects onto its local plane within --data-reach radii of some point, so no
sheet grows past a scan's edges and gaps wider than about 2 x data-reach radii stay open; and only
the points on the side of a corner's heaviest point count there, so thin parts keep both sides.
Storage: one byte per component, 56 bytes per leaf (--storage q8, thesis 4.4), floats (f32, 160
bytes), or both. Writes OUTPUT with iso_info, iso_nodes and the leaf arrays; the other sections are
carried over.
Colors: the leaves bake the points' colors, or their scanner intensities as grey levels
(--point-colors intensity: [lo, hi] to black..white, linear in radiance; SCENE.md point_colors).)";

/// "LO,HI": two finite numbers, LO < HI (CLI11 validator: "" when valid).
std::string check_range(const std::string& s) {
    const auto comma = s.find(',');
    if (comma == std::string::npos || s.find(',', comma + 1) != std::string::npos)
        return "expected LO,HI (two numbers), got '" + s + "'";
    const std::string a = s.substr(0, comma), b = s.substr(comma + 1);
    char* end_a = nullptr;
    char* end_b = nullptr;
    const double lo = std::strtod(a.c_str(), &end_a), hi = std::strtod(b.c_str(), &end_b);
    if (a.empty() || b.empty() || *end_a != '\0' || *end_b != '\0' || !std::isfinite(lo) ||
        !std::isfinite(hi) || std::fabs(lo) > 3e38 || std::fabs(hi) > 3e38)
        return "expected LO,HI (two finite numbers), got '" + s + "'";
    if (!(lo < hi)) return "LO must be below HI, got '" + s + "'";
    return {};
}

}  // namespace

int main(int argc, char** argv) {
    std::string input, output, radius = "auto", storage = "q8", stats_json, point_colors = "auto",
                               intensity_range;
    prt::iso::BuildOptions options;
    bool no_passive = false, no_balance = false, no_closure = false, keep_uncrossed = false,
         both_sides = false;
    return prt::tool::run(
        argc, argv, "prt-iso", k_description,
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("input", input, "Input pool file (positions and normals; radii optional)")
                ->required();
            app.add_option("-o,--output", output, "Output pool file (written atomically; may equal INPUT)")
                ->required();
            app.add_option("--min-level", options.min_level, "Minimum leaf level of filled leaves (root = 0)")
                ->check(CLI::Range(0u, prt::pool::k_max_iso_level));
            app.add_option("--max-level", options.max_level, "Maximum leaf level (level of detail)")
                ->check(CLI::Range(0u, prt::pool::k_max_iso_level));
            app.add_option("-X,--max-points", options.max_points,
                           "A node holding more points is split (until --max-level)")
                ->check(CLI::Range(1u, 1u << 20));
            app.add_option(
                   "--smoothing", options.smoothing,
                   "Gaussian sigma = smoothing x radius of influence (fig. 4.12: < 1 sharper, > 1 smoother)")
                ->check(CLI::Range(1e-3f, 1000.0f));
            app.add_option("--support", options.support,
                           "A point counts at a corner within this many sigmas (truncated Gaussian)")
                ->check(CLI::Range(1.0f, 10.0f));
            app.add_option("--radius", radius,
                           "Radius of influence: auto (radii section if present, else knn), radii or knn")
                ->check(CLI::IsMember({"auto", "radii", "knn"}));
            app.add_option("-k,--knn", options.knn, "k of the k-nearest-neighbour radius")
                ->check(CLI::Range(1u, 1024u));
            app.add_option("--knn-clamp", options.knn_clamp,
                           "k-NN radii above this x their median are clamped to it (0 = off)")
                ->check(CLI::Range(0.0f, 1.0e6f));
            app.add_option("--storage", storage, "Leaf arrays: q8 (56 B/leaf), f32 (160 B/leaf) or both")
                ->check(CLI::IsMember({"q8", "f32", "both"}));
            app.add_flag("--no-passive", no_passive,
                         "Do not fill passive leaves (thesis 4.3.1; leaves holes)");
            app.add_flag("--no-balance", no_balance, "Do not enforce the 2:1 level balance (thesis 4.5.1)");
            app.add_flag("--no-closure", no_closure,
                         "Do not fill the leaves behind faces the surface crosses (the surface closure; "
                         "leaves holes on noisy scans and coarse levels)");
            app.add_option(
                   "--data-reach", options.data_reach,
                   "A corner holds surface only where its projection onto the local plane lies within "
                   "this many radii of a point: gaps wider than about twice that stay open and no sheet "
                   "grows past the data (0 = off, the thesis's extrapolation)")
                ->check(CLI::Range(0.0f, 3.0f));
            app.add_flag(
                "--both-sides", both_sides,
                "Let every point within its support count at a corner (thesis eq. 4.1-4.3 as written); "
                "by default the points are split by their normal against the corner's heaviest point's and "
                "only the heavier side counts, so the two sides of a thin part do not cancel");
            app.add_flag("--keep-uncrossed", keep_uncrossed,
                         "Keep filled leaves whose corners share one sign (they hold no surface)");
            app.add_option(
                   "--point-colors", point_colors,
                   "What the leaves bake as their color: colors (the points'), intensity (their scanner "
                   "intensities as grey levels), none (white), or auto (colors, else intensity, else "
                   "none)")
                ->check(CLI::IsMember({"auto", "colors", "intensity", "none"}));
            app.add_option(
                   "--intensity-range", intensity_range,
                   "With intensity: LO,HI map to black..white (default: the 1st and 99th percentiles of "
                   "the pool's intensities)")
                ->check(CLI::Validator(check_range, "LO,HI"));
            app.add_option("-j,--threads", options.threads, "Worker threads (0 = all hardware threads)");
            app.add_option("--stats-json", stats_json, "Also write the statistics as JSON to this file");
        },
        [&](const prt::tool::CommonOptions& common) {
            using namespace prt;
            const double start = tool::now_seconds();
            options.radius = iso::parse_radius_source(radius);
            options.storage = iso::parse_storage(storage);
            options.passive = !no_passive;
            options.balance = !no_balance;
            options.closure = !no_closure;
            options.drop_uncrossed = !keep_uncrossed;
            options.one_side = !both_sides;
            try {
                iso::validate(options);
            } catch (const Error& e) {
                throw Error(std::string("invalid options: ") + e.what());
            }
            const std::filesystem::path out_dir = std::filesystem::path(output).parent_path();
            if (!out_dir.empty() && !std::filesystem::is_directory(out_dir))
                throw Error(output + ": cannot write: folder " + out_dir.string() + " does not exist");
            const pool::PoolFile in = pool::PoolFile::open(input);
            iso::BuildInput bi;
            bi.positions = in.require<pool::Float3>(pool::SectionType::positions, "prt-iso");
            if (!in.has(pool::SectionType::normals))
                throw Error(input +
                            ": no normals section: the ISO needs normals (prt-import estimates them)");
            bi.normals = in.array<pool::Float3>(pool::SectionType::normals);
            bi.radii = in.array<float>(pool::SectionType::radii);
            // The colors the leaves bake (SCENE.md point_colors; the same grey levels the player uses).
            const auto colors = in.array<pool::Rgba8>(pool::SectionType::colors);
            const auto intensities = in.array<float>(pool::SectionType::intensities);
            std::string bake = point_colors;
            if (bake == "auto")
                bake = !colors.empty() ? "colors" : !intensities.empty() ? "intensity" : "none";
            std::vector<pool::Rgba8> grey;
            std::array<float, 2> range{0, 0};
            if (bake == "colors") {
                bi.colors = colors;
            } else if (bake == "intensity") {
                if (intensities.empty())
                    throw Error(input +
                                ": no intensities section: --point-colors intensity needs one (prt-import "
                                "keeps PLY and PCD intensity)");
                if (!intensity_range.empty()) {
                    const auto comma = intensity_range.find(',');
                    range = {std::strtof(intensity_range.substr(0, comma).c_str(), nullptr),
                             std::strtof(intensity_range.substr(comma + 1).c_str(), nullptr)};
                } else {
                    range = scene::intensity_range(intensities);
                }
                std::uint64_t non_finite = 0;
                grey.resize(intensities.size());
                for (std::size_t i = 0; i < intensities.size(); ++i) {
                    non_finite += !std::isfinite(intensities[i]);
                    const std::uint8_t g = scene::intensity_grey(intensities[i], range[0], range[1]);
                    grey[i] = pool::Rgba8{g, g, g, 255};
                }
                bi.colors = grey;
                tool::note(common.quiet, "prt-iso: baking intensities [%g, %g] to black..white%s",
                           double(range[0]), double(range[1]),
                           intensity_range.empty() ? " (the 1st-99th percentile)" : "");
                if (!(range[1] > range[0]))
                    tool::note(common.quiet, "prt-iso: warning: the intensities have no spread: baked white");
                if (non_finite)
                    tool::note(common.quiet, "prt-iso: warning: %llu intensities are not finite: baked black",
                               static_cast<unsigned long long>(non_finite));
            }
            tool::note(common.quiet,
                       "prt-iso: %zu points, levels %u..%u, X = %u, smoothing %g, support %g sigma",
                       bi.positions.size(), options.min_level, options.max_level, options.max_points,
                       double(options.smoothing), double(options.support));

            iso::IsoModel model;
            {
                std::unique_ptr<tool::Progress> bar;
                std::string stage;
                auto progress = [&](const char* s, std::uint64_t done, std::uint64_t total) {
                    if (stage != s) {
                        if (bar) bar->finish();
                        stage = s;
                        bar = std::make_unique<tool::Progress>(std::string("prt-iso: ") + s, total,
                                                               common.quiet);
                    }
                    bar->update(done);
                };
                try {
                    model = iso::build_iso(bi, options, progress);
                } catch (const Error& e) {
                    throw Error(input + ": " + e.what());
                }
                if (bar) bar->finish();
            }
            const iso::BuildStats st = model.stats;
            const pool::IsoInfo info = model.info;

            pool::PoolWriter writer;
            writer.carry_over(in);
            iso::write_iso_sections(std::move(model), writer);
            const nlohmann::json parameters = {
                {"min_level", options.min_level},
                {"max_level", options.max_level},
                {"max_points", options.max_points},
                {"smoothing", options.smoothing},
                {"support", options.support},
                {"radius", iso::radius_source_name(options.radius)},
                {"radius_used", (info.flags & pool::k_iso_radii_knn) ? "knn" : "radii"},
                {"knn", options.knn},
                {"knn_clamp", options.knn_clamp},
                {"passive", options.passive},
                {"balance", options.balance},
                {"closure", options.closure},
                {"drop_uncrossed", options.drop_uncrossed},
                {"data_reach", options.data_reach},
                {"one_side", options.one_side},
                {"storage", storage},
                {"point_colors", bake}};
            nlohmann::json provenance = parameters;
            if (bake == "intensity") provenance["intensity_range"] = {range[0], range[1]};
            writer.add_provenance("prt-iso", PRT_VERSION, provenance.dump());
            const std::uint64_t bytes = writer.write(output);
            const double total = tool::now_seconds() - start;

            const double leaves = st.leaves > 0 ? double(st.leaves) : 1.0;
            if (!stats_json.empty()) {
                nlohmann::json per_level = nlohmann::json::array();
                for (std::uint32_t l = 0; l <= pool::k_max_iso_level; ++l)
                    per_level.push_back(st.leaves_per_level[l]);
                const nlohmann::json j = {{"tool", "prt-iso"},
                                          {"points", st.points},
                                          {"skipped", st.skipped},
                                          {"parameters", parameters},
                                          {"radius_median", st.radius_median},
                                          {"radii_clamped", st.radii_clamped},
                                          {"active_leaves", st.active_leaves},
                                          {"passive_leaves", st.passive_leaves},
                                          {"min_level_splits", st.min_level_splits},
                                          {"balance_splits", st.balance_splits},
                                          {"closure_leaves", st.closure_leaves},
                                          {"uncrossed_leaves", st.uncrossed_leaves},
                                          {"unsupported_corners", st.unsupported_corners},
                                          {"unsupported_leaves", st.unsupported_leaves},
                                          {"leaves", st.leaves},
                                          {"leaves_per_level", per_level},
                                          {"nodes", st.nodes},
                                          {"depth", st.depth},
                                          {"corners", st.corners},
                                          {"corner_slots", st.corner_slots},
                                          {"far_corners", st.far_corners},
                                          {"mean_neighbours", double(st.mean_neighbours_x100) / 100.0},
                                          {"iso_bytes", st.bytes},
                                          {"iso_bytes_per_leaf", double(st.bytes) / leaves},
                                          {"pool_bytes", bytes},
                                          {"seconds_radii", st.seconds_radii},
                                          {"seconds_tree", st.seconds_tree},
                                          {"seconds_passive", st.seconds_passive},
                                          {"seconds_balance", st.seconds_balance},
                                          {"seconds_corners", st.seconds_corners},
                                          {"seconds_closure", st.seconds_closure},
                                          {"seconds_encode", st.seconds_encode},
                                          {"seconds_build", st.seconds_total},
                                          {"seconds_total", total}};
                std::ofstream out(stats_json);
                out << j.dump(2) << "\n";
                if (!out) throw Error(stats_json + ": cannot write the statistics");
            }
            tool::note(common.quiet, "prt-iso: radii from %s (median %.4g%s), %llu points skipped",
                       (info.flags & pool::k_iso_radii_knn) ? "k-NN" : "the radii section", st.radius_median,
                       st.radii_clamped ? (", " + std::to_string(st.radii_clamped) + " clamped").c_str() : "",
                       static_cast<unsigned long long>(st.skipped));
            tool::note(
                common.quiet,
                "prt-iso: %llu active + %llu passive leaves (%llu split to min level, %llu by 2:1 balance), "
                "%llu more by the surface closure; %llu without a sign change and %llu away from the data "
                "dropped",
                static_cast<unsigned long long>(st.active_leaves),
                static_cast<unsigned long long>(st.passive_leaves),
                static_cast<unsigned long long>(st.min_level_splits),
                static_cast<unsigned long long>(st.balance_splits),
                static_cast<unsigned long long>(st.closure_leaves),
                static_cast<unsigned long long>(st.uncrossed_leaves),
                static_cast<unsigned long long>(st.unsupported_leaves));
            tool::note(
                common.quiet,
                "prt-iso: %llu corners (%.2f points each, %llu beyond every support) for %llu corner slots",
                static_cast<unsigned long long>(st.corners), double(st.mean_neighbours_x100) / 100.0,
                static_cast<unsigned long long>(st.far_corners),
                static_cast<unsigned long long>(st.corner_slots));
            tool::note(
                common.quiet,
                "prt-iso: %llu filled leaves, depth %u, %llu nodes; ISO %.2f MB = %.1f bytes per leaf (%s)",
                static_cast<unsigned long long>(st.leaves), st.depth,
                static_cast<unsigned long long>(st.nodes), double(st.bytes) / 1e6, double(st.bytes) / leaves,
                storage.c_str());
            tool::note(
                common.quiet,
                "prt-iso: radii %.2f s, tree %.2f s, passive %.2f s, balance %.2f s, corners %.2f s, closure "
                "%.2f s, encode %.2f s; total %.2f s; wrote %s",
                st.seconds_radii, st.seconds_tree, st.seconds_passive, st.seconds_balance, st.seconds_corners,
                st.seconds_closure, st.seconds_encode, total, output.c_str());
            if (st.leaves == 0)
                tool::note(common.quiet,
                           "prt-iso: warning: no leaf holds a surface (check the normals and levels)");
        });
}
