// prt-patches: bicubic Bezier patch files into a pool with the mixed hierarchy of seed 002, 5.1.
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "patch_build.h"
#include "patch_file.h"
#include "prt/pool_step.h"

namespace {

constexpr const char* k_description =
    R"(Read a bicubic Bezier patch file and write a pool for ray tracing it (seed 002, Nigam &
Narayanan 2012): the control points (double precision), a BVH over the patches' bounding boxes
(binned SAH, stored depth first with skip offsets), and under every patch a fixed-depth subpatch
tree of bounding boxes from de Casteljau subdivision alternating u and v, each with a cone bounding
its normals (for back-face culling).

Input formats (--format auto picks .bpt by extension, else by content):
  bpt     line 1: patch count; per patch a line "3 3" (degrees) and 16 lines "x y z"
  newell  line 1: patch count P; P lines of 16 comma-separated 1-based vertex indices (the 4x4
          net, row major); a line with the vertex count V; V lines "x,y,z" (the Utah teapot files)
Any error in the file (wrong counts, an index out of range, a non-number, NaN) stops with one line
naming the file and line; nothing is written then.

--orient outward transposes patches (swapping u and v) so that dQ/du x dQ/dv agrees across shared
edges and points away from the model; the pool is marked oriented when no conflict remains and no
edge joins three or more patches, and only then may a renderer cull back faces or use front/back
ray flags on it. The surface itself is unchanged either way.)";

/// The options of prt-patches.
struct Options {
    std::string input;
    std::string format = "auto";
    std::uint32_t depth = 6;
    std::uint32_t bins = 16;
    std::string orient = "outward";
};

void report(const prt::tool::PoolStep& step, const prt::patches::PatchModel& model, bool orient,
            std::size_t count, std::uint32_t depth) {
    const prt::patches::OrientStats& o = model.orient;
    if (orient)
        step.note(
            "prt-patches: orientation: %u components, %u patches transposed, %u shared / %u boundary / %u "
            "non-manifold / %u collapsed edges, %u conflicts, %u flat components (file's side kept)%s",
            o.components, o.flipped, o.shared_edges, o.boundary_edges, o.nonmanifold_edges, o.collapsed_edges,
            o.conflicts, o.flat_components,
            (o.conflicts || o.nonmanifold_edges) ? " (not marked oriented: shade two-sided, no culling)"
                                                 : "");
    step.note(
        "prt-patches: %zu patches (%u with collapsed edges), BVH %zu nodes, depth %u, SAH %.2f; %zu "
        "subpatch boxes (depth %u)",
        count, model.degenerate_patches, model.bvh.size(), model.bvh_stats.depth, model.bvh_stats.sah_cost,
        model.nodes.size(), depth);
}

void patches_step(prt::tool::PoolStep& step, const Options& o) {
    namespace pp = prt::patches;
    step.check_output_folder();
    pp::PatchSet set = pp::read_patch_file(o.input, pp::parse_patch_format(o.format));
    const std::size_t count = set.nets.size();
    step.note("prt-patches: read %s: %zu patches (%s format) in %.3f s", o.input.c_str(), count,
              pp::patch_format_name(set.format), step.seconds());

    pp::BuildOptions options;
    options.depth = o.depth;
    options.bins = o.bins;
    options.orient = o.orient == "outward";
    pp::PatchModel model;
    {
        prt::tool::Progress bar("prt-patches: subpatch trees", count, step.quiet());
        model = pp::build_patch_model(std::move(set.nets), options,
                                      [&](std::uint64_t done, std::uint64_t) { bar.update(done); });
        bar.finish();
    }
    report(step, model, options.orient, count, o.depth);

    pp::write_patch_sections(model, step.writer());
    const nlohmann::json params = {{"input", std::filesystem::path(o.input).filename().string()},
                                   {"format", pp::patch_format_name(set.format)},
                                   {"depth", o.depth},
                                   {"bins", o.bins},
                                   {"orient", o.orient},
                                   {"patches", count},
                                   {"oriented", (model.patch_info.flags & prt::pool::k_patch_oriented) != 0}};
    const std::uint64_t bytes = step.write(params);
    step.note("prt-patches: wrote %s: %.2f MB (%.0f bytes per patch) in %.3f s total",
              step.output_path().c_str(), double(bytes) / 1e6, double(bytes) / double(count), step.seconds());
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    prt::tool::PoolStep step("prt-patches", k_description, prt::tool::PoolStep::generator_help());
    return step.run(
        argc, argv,
        [&](CLI::App& app) {
            app.add_option("input", o.input, "Patch file (.bpt or Newell format)")->required();
            app.add_option("--format", o.format, "Input format: auto, bpt or newell")
                ->check(CLI::IsMember({"auto", "bpt", "newell"}));
            app.add_option("--depth", o.depth,
                           "Subpatch tree depth: 2^(depth+1)-1 boxes per patch (seed 002 uses 6)")
                ->check(CLI::Range(0u, prt::pool::k_max_subpatch_depth));
            app.add_option("--bins", o.bins, "SAH bins per axis when building the BVH")
                ->check(CLI::Range(2u, 1024u));
            app.add_option(
                   "--orient", o.orient,
                   "outward (make the u/v orientation consistent, normals away from the model) or none "
                   "(keep the file's)")
                ->check(CLI::IsMember({"outward", "none"}));
        },
        [&](prt::tool::PoolStep& s) { patches_step(s, o); });
}
