// prt-patches: bicubic Bezier patch files into a pool with the mixed hierarchy of seed 002, 5.1.
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "patch_build.h"
#include "patch_file.h"
#include "prt/formats/pool.h"
#include "prt/tool.h"

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

}  // namespace

int main(int argc, char** argv) {
    std::string input;
    std::string output;
    std::string format = "auto";
    std::uint32_t depth = 6;
    std::uint32_t bins = 16;
    std::string orient = "outward";

    return prt::tool::run(
        argc, argv, "prt-patches", k_description,
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("input", input, "Patch file (.bpt or Newell format)")->required();
            app.add_option("-o,--output", output, "Pool file to write (replaced atomically)")->required();
            app.add_option("--format", format, "Input format: auto, bpt or newell")
                ->check(CLI::IsMember({"auto", "bpt", "newell"}));
            app.add_option("--depth", depth,
                           "Subpatch tree depth: 2^(depth+1)-1 boxes per patch (seed 002 uses 6)")
                ->check(CLI::Range(0u, prt::pool::k_max_subpatch_depth));
            app.add_option("--bins", bins, "SAH bins per axis when building the BVH")
                ->check(CLI::Range(2u, 1024u));
            app.add_option("--orient", orient,
                           "outward (make the u/v orientation consistent, normals away from the model) "
                           "or none (keep the file's)")
                ->check(CLI::IsMember({"outward", "none"}));
        },
        [&](const prt::tool::CommonOptions& common) {
            namespace pp = prt::patches;
            const std::filesystem::path out_dir = std::filesystem::path(output).parent_path();
            if (!out_dir.empty() && !std::filesystem::is_directory(out_dir))
                throw prt::Error(output + ": cannot write: folder " + out_dir.string() + " does not exist");
            const double t0 = prt::tool::now_seconds();
            pp::PatchSet set = pp::read_patch_file(input, pp::parse_patch_format(format));
            const std::size_t count = set.nets.size();
            prt::tool::note(common.quiet, "prt-patches: read %s: %zu patches (%s format) in %.3f s",
                            input.c_str(), count, pp::patch_format_name(set.format),
                            prt::tool::now_seconds() - t0);

            pp::BuildOptions options;
            options.depth = depth;
            options.bins = bins;
            options.orient = orient == "outward";
            pp::PatchModel model;
            {
                prt::tool::Progress bar("prt-patches: subpatch trees", count, common.quiet);
                model = pp::build_patch_model(std::move(set.nets), options,
                                              [&](std::uint64_t done, std::uint64_t) { bar.update(done); });
                bar.finish();
            }
            const pp::OrientStats& o = model.orient;
            if (options.orient)
                prt::tool::note(
                    common.quiet,
                    "prt-patches: orientation: %u components, %u patches transposed, %u shared / %u "
                    "boundary / %u non-manifold / %u collapsed edges, %u conflicts%s",
                    o.components, o.flipped, o.shared_edges, o.boundary_edges, o.nonmanifold_edges,
                    o.collapsed_edges, o.conflicts,
                    (o.conflicts || o.nonmanifold_edges)
                        ? " (not marked oriented: shade two-sided, no culling)"
                        : "");
            prt::tool::note(
                common.quiet,
                "prt-patches: %zu patches (%u with collapsed edges), BVH %zu nodes, depth %u, SAH %.2f; "
                "%zu subpatch boxes (depth %u)",
                count, model.degenerate_patches, model.bvh.size(), model.bvh_stats.depth,
                model.bvh_stats.sah_cost, model.nodes.size(), depth);

            prt::pool::PoolWriter writer;
            pp::write_patch_sections(model, writer);
            nlohmann::json params = {
                {"input", std::filesystem::path(input).filename().string()},
                {"format", pp::patch_format_name(set.format)},
                {"depth", depth},
                {"bins", bins},
                {"orient", orient},
                {"patches", count},
                {"oriented", (model.patch_info.flags & prt::pool::k_patch_oriented) != 0}};
            writer.add_provenance("prt-patches", PRT_VERSION, params.dump());
            const std::uint64_t bytes = writer.write(output);
            prt::tool::note(common.quiet,
                            "prt-patches: wrote %s: %.2f MB (%.0f bytes per patch) in %.3f s total",
                            output.c_str(), double(bytes) / 1e6, double(bytes) / double(count),
                            prt::tool::now_seconds() - t0);
        });
}
