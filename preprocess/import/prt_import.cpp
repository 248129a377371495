// prt-import: scans, merged scans (a pose list) or meshes -> pool (model_info, positions, normals,
// colors, intensities, radii, sensors, scan_ids).
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "import.h"
#include "out_of_core.h"
#include "poses.h"
#include "prt/pool_step.h"

namespace imp = prt::pre::import;

namespace {

/// The command line of prt-import.
struct Cli {
    std::vector<std::string> inputs;
    std::string poses;
    std::string format = "auto";
    std::string normals = "auto";
    std::string mesh_mode = "auto";
    std::string sample_normals = "face";
    std::vector<double> sensor, sensor_direction;
    imp::Options options;
    bool keep_outliers = false;
    std::string memory;        ///< --memory text; empty = half the physical memory
    std::string spill_folder;  ///< empty = the output's folder
    std::uint64_t tile_points = 0;

    void declare(CLI::App& app);
    /// The import options the command line names.
    imp::Options import_options(bool quiet);
};

void Cli::declare(CLI::App& app) {
    app.footer(
        "Formats: PLY (ascii, binary little/big endian; vertex x y z, optional nx ny nz, red green blue\n"
        "[alpha] (uchar 0..255, ushort 0..65535 or float 0..1; other values, or a colour list, are an\n"
        "error), radius, intensity / scalar_Intensity / reflectance; a camera element's view_px view_py\n"
        "view_pz is the scanner; other properties and elements skipped), XYZ text (x y z or x y z nx ny\n"
        "nz per line, space or comma separated, # comments), PCD (via PCL; x y z, optional normal_x..,\n"
        "rgb/rgba (SIZE 4), intensity; VIEWPOINT tx ty tz qw qx qy qz is the scanner at (tx, ty, tz);\n"
        "NaN entries of organized clouds dropped), pools (.pool: points, normals, colors, intensities,\n"
        "sensors, scan_ids; their provenance is kept), meshes (PLY with faces, OBJ, OFF, STL via\n"
        "OpenMesh: vertices with area-weighted normals, or --sample).\n"
        "Merged scans: --poses FILE reads every scan a Stanford .conf (bmesh FILE tx ty tz qi qj qk qr:\n"
        "p -> R(q)^-1 p + t, the scanner far along +z of the scan's frame) or a JSON pose list names\n"
        "(preprocess/import/README.md), or only the INPUTs given; each scan is cleaned and rid of\n"
        "outliers in its own frame, then moved and merged (one sensor per scan, scan_ids per point).\n"
        "Outliers (on by default, per scan, not for meshes): statistical (mean distance to the\n"
        "--outlier-k nearest neighbours above mean + --outlier-std x std over the scan, as PCL's\n"
        "StatisticalOutlierRemoval) or radius (fewer than --outlier-min-neighbours others within\n"
        "--outlier-radius x the scan's median spacing, the median of that mean distance).\n"
        "Normals: estimated by PCA over k neighbours when missing (ours, every build), facing each\n"
        "point's sensor (PCD VIEWPOINT, PLY camera, pose list, pool, --sensor / --sensor-direction),\n"
        "those more than acos(--grazing-cos) from their line of sight taking their sign from their\n"
        "neighbours; without a sensor, by propagation over the k-NN graph (Hoppe 1992) from each\n"
        "component's highest point (+z outward). Grazing (ambiguous) counts are reported. The\n"
        "measurements behind the defaults: preprocess/import/README.md. Dropped points (NaN/Inf,\n"
        "zero normals, duplicates, outliers, malformed lines) are counted on stderr. Out of core\n"
        "(--memory): PLY or XYZ point sets whose in-core import needs more are streamed and worked\n"
        "tile by tile with the same result (preprocess/import/README.md). On any error\n"
        "nothing is written and the exit code is 1 (2 for bad usage).");
    app.add_option("inputs", inputs,
                   "Scan, mesh or pool to import (.ply .pcd .xyz .txt .obj .off .stl .pool); with --poses: "
                   "none (every scan of the pose file) or those of its scans to merge");
    app.add_option("--poses", poses,
                   "Pose list (Stanford .conf or JSON) naming the scans to merge and their rigid transforms "
                   "(default: none, one input)");
    app.add_option("--format", format,
                   "Input format: auto (by extension, then by content), ply, pcd, xyz, mesh, pool")
        ->check(CLI::IsMember({"auto", "ply", "pcd", "xyz", "mesh", "pool"}));
    app.add_option("--normals", normals,
                   "auto: keep the file's normals, estimate by PCA only when it has none (meshes: "
                   "area-weighted vertex normals, the file's where faces cancel); keep: never estimate "
                   "(a file without normals gives a pool without normals; meshes: the file's vertex "
                   "normals, area-weighted where it has none); estimate: always PCA, ignoring the file's")
        ->check(CLI::IsMember({"auto", "keep", "estimate"}));
    app.add_option("--mesh-mode", mesh_mode,
                   "A PLY with faces is read as: auto (a mesh when it has faces and no vertex normals, "
                   "else points; points when this build lacks OpenMesh), points (the vertex element "
                   "only), mesh (through OpenMesh)")
        ->check(CLI::IsMember({"auto", "points", "mesh"}));
    app.add_option("--sample", options.sample,
                   "Meshes: sample this many points uniformly over the surface by area instead of "
                   "taking the vertices (0 = vertices)");
    app.add_option("--seed", options.seed,
                   "Random seed for --sample and --keep-fraction (same seed, same points)");
    app.add_option("--sample-normals", sample_normals,
                   "Normals of sampled points: face (the normal of the triangle sampled) or "
                   "interpolated (area-weighted vertex normals blended barycentrically)")
        ->check(CLI::IsMember({"face", "interpolated"}));
    app.add_option("-k,--k", options.k, "Neighbours for PCA normal estimation and orientation")
        ->check(CLI::Range(3, 256));
    auto* o_sensor = app.add_option("--sensor", sensor,
                                    "X,Y,Z: one point sensor (the scanner position, output frame) for every "
                                    "point, replacing the files' (default: the files' sensors, else none)")
                         ->delimiter(',')
                         ->expected(3);
    auto* o_direction =
        app.add_option("--sensor-direction", sensor_direction,
                       "X,Y,Z: one far sensor, the direction from the scene toward it (output frame), "
                       "replacing the files' (default: the files' sensors, else none)")
            ->delimiter(',')
            ->expected(3);
    auto* o_none = app.add_flag("--no-sensor", options.no_sensor,
                                "Ignore every sensor of the files and the pose list: orient estimated "
                                "normals by propagation, write no sensors");
    app.add_option("--grazing-cos", options.grazing_cos,
                   "With a sensor: estimated normals whose |cos| to their line of sight is below this "
                   "take their sign from the normals around them over the k-NN graph, the others from "
                   "their sensor (0: every sign from the sensor)")
        ->check(CLI::Range(0.0, 1.0));
    o_sensor->excludes(o_direction);
    o_none->excludes(o_sensor);
    o_none->excludes(o_direction);
    app.add_flag("--keep-outliers", keep_outliers, "Do not remove outliers (default: remove them, per scan)");
    app.add_option("--outlier-k", options.outliers.k,
                   "Outliers: neighbours whose mean distance measures a point's isolation")
        ->check(CLI::Range(1, 256));
    app.add_option("--outlier-std", options.outliers.std_ratio,
                   "Statistical outliers: mean k-NN distance above the scan's mean + this x standard "
                   "deviation (0: no statistical test)")
        ->check(CLI::Range(0.0, 1e6));
    app.add_option("--outlier-radius", options.outliers.radius_factor,
                   "Radius outliers: the radius as a multiple of the scan's median spacing (median "
                   "of the mean k-NN distance) (0: no radius test)")
        ->check(CLI::Range(0.0, 1e6));
    app.add_option("--outlier-min-neighbours", options.outliers.min_neighbours,
                   "Radius outliers: fewer than this many other points within the radius (at most "
                   "--outlier-k)")
        ->check(CLI::Range(0, 256));
    app.add_option("--keep-fraction", options.keep_fraction,
                   "Keep this fraction of each scan's points, chosen by --seed before anything else "
                   "(decimation; mesh vertices keep their normals from the whole mesh)")
        ->check(CLI::Range(1e-6, 1.0));
    app.add_flag("--keep-duplicates", options.keep_duplicates,
                 "Keep exactly coincident points (default: keep the first, drop and count the rest)");
    prt::tool::PoolStep::add_memory(
        app, memory,
        "Memory the import may use (K, M, G suffixes: 512M, 4G); a PLY or XYZ point set (or a "
        "pose list of them) whose in-core import needs more is imported out of core: read in "
        "chunks, duplicates, outliers and normals tile by tile, the sections in spill files, with the "
        "in-core result; other inputs and options that need the whole point set fail naming it "
        "(default: half the physical memory)");
    app.add_option("--spill-folder", spill_folder,
                   "Folder of the out-of-core spill files (removed as soon as created; about 60 + 4k "
                   "bytes per point) (default: the output's folder)");
    app.add_option("--tile-points", tile_points,
                   "Testing: force the out-of-core import with k-NN tiles of this many points")
        ->group("");
    app.callback([&] {
        if (poses.empty() && inputs.size() != 1)
            throw CLI::ValidationError("inputs", inputs.empty()
                                                     ? "an input file is required (or --poses FILE)"
                                                     : "several inputs need --poses (a pose list)");
        if (options.outliers.min_neighbours > options.outliers.k)
            throw CLI::ValidationError("--outlier-min-neighbours", "must not exceed --outlier-k");
    });
}

imp::Options Cli::import_options(bool quiet) {
    options.quiet = quiet;
    options.format = format == "ply"    ? imp::Format::ply
                     : format == "pcd"  ? imp::Format::pcd
                     : format == "xyz"  ? imp::Format::xyz
                     : format == "mesh" ? imp::Format::mesh
                     : format == "pool" ? imp::Format::pool
                                        : imp::Format::automatic;
    options.normals = normals == "keep"       ? imp::NormalsMode::keep
                      : normals == "estimate" ? imp::NormalsMode::estimate
                                              : imp::NormalsMode::automatic;
    options.mesh_mode = mesh_mode == "points" ? imp::MeshMode::points
                        : mesh_mode == "mesh" ? imp::MeshMode::mesh
                                              : imp::MeshMode::automatic;
    options.sample_normals =
        sample_normals == "interpolated" ? imp::SampleNormals::interpolated : imp::SampleNormals::face;
    if (sensor.size() == 3) options.sensor = std::array<double, 3>{sensor[0], sensor[1], sensor[2]};
    if (sensor_direction.size() == 3)
        options.sensor_direction =
            std::array<double, 3>{sensor_direction[0], sensor_direction[1], sensor_direction[2]};
    options.outliers.enabled = !keep_outliers;

    return options;
}

/// Whether the import runs out of core (--memory, issue 17); throws the one-line error when it
/// would have to and cannot.
bool out_of_core(const Cli& cli, const imp::Options& options, const std::vector<std::filesystem::path>& paths,
                 std::uint64_t memory) {
    using prt::tool::format_bytes;
    const std::string forced = cli.tile_points > 0 ? " (--tile-points forces the out-of-core import)" : "";
    if (!cli.poses.empty()) {
        // Merged scans: the sum of the scans' in-core estimates; out of core when every scan can be.
        std::uint64_t bytes = 0;
        std::string unsupported;
        try {
            const std::vector<imp::PoseEntry> entries = imp::read_poses(cli.poses);
            if (entries.size() == 1 && entries[0].pose.is_identity())
                unsupported = cli.poses +
                              ": one scan at the identity pose is not merged out of core (import the "
                              "scan itself)";
            for (const imp::PoseEntry& entry : entries) {
                if (!paths.empty()) {
                    std::error_code ec;
                    const auto a = std::filesystem::weakly_canonical(entry.file, ec);
                    bool listed = false;
                    for (const auto& p : paths)
                        listed = listed || std::filesystem::weakly_canonical(p, ec) == a;
                    if (!listed) continue;
                }
                const imp::ImportEstimate e =
                    imp::estimate_import(entry.file, options, entry.sensor_given && entry.sensor.has_value());
                bytes += e.bytes;
                if (unsupported.empty()) unsupported = e.unsupported;
            }
        } catch (const prt::Error&) {
            return false;  // the in-core import reports the bad pose list or scan
        }
        if (bytes <= memory && cli.tile_points == 0) return false;
        if (!unsupported.empty())
            throw prt::Error(unsupported + "; the in-core import of the merged scans needs about " +
                             format_bytes(bytes) + ", --memory is " + format_bytes(memory) + forced +
                             ": raise --memory");
        return true;
    }
    // Small files go in core without a look inside: the in-core import holds at most about 160
    // bytes per byte of input (460 bytes per point, at least 3 bytes per point in any format).
    std::error_code ec;
    const std::uint64_t file_bytes = std::filesystem::file_size(paths[0], ec);
    if (cli.tile_points == 0 && !ec && file_bytes <= memory / 160) return false;
    imp::ImportEstimate e;
    try {
        e = imp::estimate_import(paths[0], options);
    } catch (const prt::Error&) {
        return false;  // the in-core import reports the unreadable input
    }
    if (e.bytes <= memory && cli.tile_points == 0) return false;
    if (!e.unsupported.empty())
        throw prt::Error(e.unsupported + "; the in-core import needs about " + format_bytes(e.bytes) +
                         ", --memory is " + format_bytes(memory) + forced + ": raise --memory");
    return true;
}

/// A pool input's provenance comes first (prt-synth's scans keep their shape for the error
/// measurements); its other sections are computed again by the later steps. `source` holds the
/// pool the writer's carried views point into.
void carry_provenance(imp::Report& report, prt::pool::PoolWriter& writer,
                      std::optional<prt::pool::PoolFile>& source) {
    if (report.pools.empty()) return;
    source.emplace(prt::pool::PoolFile::open(report.pools.front()));
    writer.carry_over(*source);
    for (const prt::pool::SectionEntry& e : source->sections())
        writer.remove(static_cast<prt::pool::SectionType>(e.type));
    if (report.pools.size() > 1)
        report.notes.push_back("provenance: kept that of " + report.pools.front().string() +
                               "; the other pool inputs are named in prt-import's parameters");
}

void import_step(prt::tool::PoolStep& step, Cli& cli) {
    const imp::Options options = cli.import_options(step.quiet());
    imp::Report report;
    std::vector<std::filesystem::path> paths(cli.inputs.begin(), cli.inputs.end());
    const std::uint64_t memory = prt::tool::memory_limit(cli.memory);
    if (out_of_core(cli, options, paths, memory)) {
        imp::MemoryParams mem;
        mem.memory = memory;
        mem.tile_points = cli.tile_points;
        mem.spill_folder = !cli.spill_folder.empty()
                               ? std::filesystem::path(cli.spill_folder)
                               : std::filesystem::absolute(step.output_path()).parent_path();
        const imp::SpilledCloud cloud =
            cli.poses.empty() ? imp::import_file_out_of_core(paths[0], options, mem, report)
                              : imp::import_merged_out_of_core(cli.poses, paths, options, mem, report);
        std::optional<prt::pool::PoolFile> source;
        carry_provenance(report, step.writer(), source);
        imp::write_point_sections(cloud, mem, step.writer());
        const double t0 = prt::tool::now_seconds();
        const std::uint64_t bytes = step.write(imp::options_json(paths, cli.poses, options));
        for (const std::string& line : report.summary_lines()) step.note("%s", line.c_str());
        step.note("wrote %s: %llu points%s%s%s%s, %llu bytes in %.3f s (out of core, peak RSS %s)",
                  step.output_path().c_str(), static_cast<unsigned long long>(cloud.size),
                  cloud.normals.file ? ", normals" : "", cloud.colors.file ? ", colors" : "",
                  cloud.intensities.file ? ", intensities" : "", cloud.radii.file ? ", radii" : "",
                  static_cast<unsigned long long>(bytes), prt::tool::now_seconds() - t0,
                  prt::tool::format_bytes(prt::pre::peak_rss_bytes()).c_str());
        return;
    }
    const prt::pre::PointCloud cloud = cli.poses.empty()
                                           ? imp::import_file(paths[0], options, report)
                                           : imp::import_merged(cli.poses, paths, options, report);
    prt::pool::PoolWriter& writer = step.writer();
    std::optional<prt::pool::PoolFile> source;
    carry_provenance(report, writer, source);
    prt::pre::write_point_sections(cloud, writer);
    const double t0 = prt::tool::now_seconds();
    const std::uint64_t bytes = step.write(imp::options_json(paths, cli.poses, options));
    for (const std::string& line : report.summary_lines()) step.note("%s", line.c_str());
    step.note("wrote %s: %llu points%s%s%s%s, %llu bytes in %.3f s", step.output_path().c_str(),
              static_cast<unsigned long long>(cloud.size()), cloud.has_normals() ? ", normals" : "",
              cloud.has_colors() ? ", colors" : "", cloud.has_intensities() ? ", intensities" : "",
              cloud.has_radii() ? ", radii" : "", static_cast<unsigned long long>(bytes),
              prt::tool::now_seconds() - t0);
}

}  // namespace

int main(int argc, char** argv) {
    Cli cli;
    prt::tool::PoolStep step(
        "prt-import",
        "Imports a scan (PLY, XYZ, PCD, pool), merged scans (--poses) or a mesh (PLY, OBJ, "
        "OFF, STL) into a pool file",
        prt::tool::PoolStep::generator_help("Pool file to write (written atomically)"));
    return step.run(
        argc, argv, [&](CLI::App& app) { cli.declare(app); },
        [&](prt::tool::PoolStep& s) { import_step(s, cli); });
}
