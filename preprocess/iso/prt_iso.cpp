// prt-iso: the Implicit Surface Octree of thesis ch. 4 from a pool's points and normals.
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "iso_build.h"
#include "iso_pool.h"
#include "prt/formats/scene.h"
#include "prt/pool_step.h"

namespace prt::iso {

// --stats-json: the statistics whose keys are their member names; stats_json() adds the others.
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(BuildStats, points, skipped, radius_median, radii_clamped, active_leaves,
                                   passive_leaves, min_level_splits, balance_splits, closure_leaves,
                                   uncrossed_leaves, unsupported_corners, unsupported_leaves, leaves, nodes,
                                   depth, corners, corner_slots, far_corners, seconds_radii, seconds_tree,
                                   seconds_passive, seconds_balance, seconds_corners, seconds_closure,
                                   seconds_encode)

}  // namespace prt::iso

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

using ull = unsigned long long;

/// The colors the leaves bake (SCENE.md point_colors; the same grey levels the player uses).
struct Bake {
    std::string what;                    ///< colors, intensity or none
    std::vector<prt::pool::Rgba8> grey;  ///< intensity: the grey levels
    std::array<float, 2> range{0, 0};    ///< intensity: the range mapped to black..white
};

Bake choose_colors(prt::tool::PoolStep& step, const std::string& point_colors,
                   const std::string& intensity_range, prt::iso::BuildInput& bi) {
    using namespace prt;
    const pool::PoolFile& in = step.input();
    const auto colors = in.array<pool::Rgba8>(pool::SectionType::colors);
    const auto intensities = in.array<float>(pool::SectionType::intensities);
    Bake b;
    b.what = point_colors;
    if (b.what == "auto") b.what = !colors.empty() ? "colors" : !intensities.empty() ? "intensity" : "none";
    if (b.what == "colors") bi.colors = colors;
    if (b.what != "intensity") return b;
    if (intensities.empty())
        throw Error(
            step.input_path() +
            ": no intensities section: --point-colors intensity needs one (prt-import keeps PLY and PCD "
            "intensity)");
    if (!intensity_range.empty()) {
        const auto comma = intensity_range.find(',');
        b.range = {std::strtof(intensity_range.substr(0, comma).c_str(), nullptr),
                   std::strtof(intensity_range.substr(comma + 1).c_str(), nullptr)};
    } else {
        b.range = scene::intensity_range(intensities);
    }
    std::uint64_t non_finite = 0;
    b.grey.resize(intensities.size());
    for (std::size_t i = 0; i < intensities.size(); ++i) {
        non_finite += !std::isfinite(intensities[i]);
        const std::uint8_t g = scene::intensity_grey(intensities[i], b.range[0], b.range[1]);
        b.grey[i] = pool::Rgba8{g, g, g, 255};
    }
    bi.colors = b.grey;
    step.note("prt-iso: baking intensities [%g, %g] to black..white%s", double(b.range[0]),
              double(b.range[1]), intensity_range.empty() ? " (the 1st-99th percentile)" : "");
    if (!(b.range[1] > b.range[0]))
        step.note("prt-iso: warning: the intensities have no spread: baked white");
    if (non_finite)
        step.note("prt-iso: warning: %llu intensities are not finite: baked black", ull(non_finite));
    return b;
}

nlohmann::json stats_json(const prt::iso::BuildStats& st) {
    nlohmann::json j = st;
    nlohmann::json per_level = nlohmann::json::array();
    for (std::uint32_t l = 0; l <= prt::pool::k_max_iso_level; ++l)
        per_level.push_back(st.leaves_per_level[l]);
    j["leaves_per_level"] = per_level;
    j["mean_neighbours"] = double(st.mean_neighbours_x100) / 100.0;
    j["iso_bytes"] = st.bytes;
    j["iso_bytes_per_leaf"] = double(st.bytes) / (st.leaves > 0 ? double(st.leaves) : 1.0);
    j["seconds_build"] = st.seconds_total;
    return j;
}

void report(const prt::tool::PoolStep& step, const prt::iso::BuildStats& st, const prt::pool::IsoInfo& info,
            const std::string& storage, double total) {
    using namespace prt;
    const double leaves = st.leaves > 0 ? double(st.leaves) : 1.0;
    step.note("prt-iso: radii from %s (median %.4g%s), %llu points skipped",
              (info.flags & pool::k_iso_radii_knn) ? "k-NN" : "the radii section", st.radius_median,
              st.radii_clamped ? (", " + std::to_string(st.radii_clamped) + " clamped").c_str() : "",
              ull(st.skipped));
    step.note(
        "prt-iso: %llu active + %llu passive leaves (%llu split to min level, %llu by 2:1 balance), %llu "
        "more by the surface closure; %llu without a sign change and %llu away from the data dropped",
        ull(st.active_leaves), ull(st.passive_leaves), ull(st.min_level_splits), ull(st.balance_splits),
        ull(st.closure_leaves), ull(st.uncrossed_leaves), ull(st.unsupported_leaves));
    step.note("prt-iso: %llu corners (%.2f points each, %llu beyond every support) for %llu corner slots",
              ull(st.corners), double(st.mean_neighbours_x100) / 100.0, ull(st.far_corners),
              ull(st.corner_slots));
    step.note("prt-iso: %llu filled leaves, depth %u, %llu nodes; ISO %.2f MB = %.1f bytes per leaf (%s)",
              ull(st.leaves), st.depth, ull(st.nodes), double(st.bytes) / 1e6, double(st.bytes) / leaves,
              storage.c_str());
    step.note(
        "prt-iso: radii %.2f s, tree %.2f s, passive %.2f s, balance %.2f s, corners %.2f s, closure %.2f "
        "s, encode %.2f s; total %.2f s; wrote %s",
        st.seconds_radii, st.seconds_tree, st.seconds_passive, st.seconds_balance, st.seconds_corners,
        st.seconds_closure, st.seconds_encode, total, step.output_path().c_str());
    if (st.leaves == 0) step.note("prt-iso: warning: no leaf holds a surface (check the normals and levels)");
}

void iso_step(prt::tool::PoolStep& step, const prt::iso::BuildOptions& options, const std::string& storage,
              const std::string& point_colors, const std::string& intensity_range) {
    using namespace prt;
    step.check_output_folder();
    const pool::PoolFile& in = step.input();
    iso::BuildInput bi;
    bi.positions = in.require<pool::Float3>(pool::SectionType::positions, "prt-iso");
    if (!in.has(pool::SectionType::normals))
        throw Error(step.input_path() +
                    ": no normals section: the ISO needs normals (prt-import estimates them)");
    bi.normals = in.array<pool::Float3>(pool::SectionType::normals);
    bi.radii = in.array<float>(pool::SectionType::radii);
    const Bake bake = choose_colors(step, point_colors, intensity_range, bi);
    step.note("prt-iso: %zu points, levels %u..%u, X = %u, smoothing %g, support %g sigma",
              bi.positions.size(), options.min_level, options.max_level, options.max_points,
              double(options.smoothing), double(options.support));

    tool::StagedProgress progress("prt-iso", step.quiet());
    iso::IsoModel model = step.about_input([&] {
        return iso::build_iso(bi, options, [&](const char* stage, std::uint64_t done, std::uint64_t total) {
            progress.update(stage, done, total);
        });
    });
    progress.finish();
    const iso::BuildStats st = model.stats;
    const pool::IsoInfo info = model.info;

    iso::write_iso_sections(std::move(model), step.writer());
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
        {"point_colors", bake.what}};
    nlohmann::json provenance = parameters;
    if (bake.what == "intensity") provenance["intensity_range"] = {bake.range[0], bake.range[1]};
    const std::uint64_t bytes = step.write(provenance);
    const double total = step.seconds();

    nlohmann::json j = stats_json(st);
    j["parameters"] = parameters;
    j["pool_bytes"] = bytes;
    j["seconds_total"] = total;
    step.write_stats(std::move(j));
    report(step, st, info, storage, total);
}

}  // namespace

int main(int argc, char** argv) {
    std::string radius = "auto", storage = "q8", point_colors = "auto", intensity_range;
    prt::iso::BuildOptions options;
    bool no_passive = false, no_balance = false, no_closure = false, keep_uncrossed = false,
         both_sides = false;
    prt::tool::PoolStep step("prt-iso", k_description,
                             {.input = "Input pool file (positions and normals; radii optional)"});
    return step.run(
        argc, argv,
        [&](CLI::App& app) {
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
            app.add_flag(
                "--no-closure", no_closure,
                "Do not fill the leaves behind faces the surface crosses (the surface closure; leaves "
                "holes on noisy scans and coarse levels)");
            app.add_option(
                   "--data-reach", options.data_reach,
                   "A corner holds surface only where its projection onto the local plane lies within "
                   "this many radii of a point: gaps wider than about twice that stay open and no sheet "
                   "grows past the data (0 = off, the thesis's extrapolation)")
                ->check(CLI::Range(0.0f, 3.0f));
            app.add_flag(
                "--both-sides", both_sides,
                "Let every point within its support count at a corner (thesis eq. 4.1-4.3 as written); "
                "by default the points are split by their normal against the corner's heaviest point's "
                "and only the heavier side counts, so the two sides of a thin part do not cancel");
            app.add_flag("--keep-uncrossed", keep_uncrossed,
                         "Keep filled leaves whose corners share one sign (they hold no surface)");
            app.add_option(
                   "--point-colors", point_colors,
                   "What the leaves bake as their color: colors (the points'), intensity (their scanner "
                   "intensities as grey levels), none (white), or auto (colors, else intensity, else none)")
                ->check(CLI::IsMember({"auto", "colors", "intensity", "none"}));
            app.add_option(
                   "--intensity-range", intensity_range,
                   "With intensity: LO,HI map to black..white (default: the 1st and 99th percentiles of "
                   "the pool's intensities)")
                ->check(CLI::Validator(check_range, "LO,HI"));
            prt::tool::PoolStep::add_threads(app, options.threads);
        },
        [&](prt::tool::PoolStep& s) {
            using namespace prt;
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
            iso_step(s, options, storage, point_colors, intensity_range);
        });
}
