#include "import.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "mapped_file.h"
#include "mesh.h"
#include "orient.h"
#include "pcl_backend.h"
#include "ply_reader.h"
#include "prt/error.h"
#include "prt/tool.h"
#include "xyz_reader.h"

namespace prt::pre::import {

namespace {

std::string lower_extension(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    return ext;
}

const char* format_name(Format f) {
    switch (f) {
        case Format::automatic:
            return "auto";
        case Format::ply:
            return "ply";
        case Format::pcd:
            return "pcd";
        case Format::xyz:
            return "xyz";
        case Format::mesh:
            return "mesh";
    }
    return "?";
}

const char* normals_name(NormalsMode m) {
    switch (m) {
        case NormalsMode::automatic:
            return "auto";
        case NormalsMode::keep:
            return "keep";
        case NormalsMode::estimate:
            return "estimate";
    }
    return "?";
}

const char* mesh_mode_name(MeshMode m) {
    switch (m) {
        case MeshMode::automatic:
            return "auto";
        case MeshMode::points:
            return "points";
        case MeshMode::mesh:
            return "mesh";
    }
    return "?";
}

std::string fmt(const char* format, double a) {
    char buf[64];
    std::snprintf(buf, sizeof buf, format, a);
    return buf;
}

}  // namespace

Format detect_format(const std::filesystem::path& path) {
    const std::string ext = lower_extension(path);
    if (ext == ".ply") return Format::ply;
    if (ext == ".pcd") return Format::pcd;
    if (ext == ".xyz" || ext == ".txt" || ext == ".csv") return Format::xyz;
    if (ext == ".obj" || ext == ".off" || ext == ".stl") return Format::mesh;
    // Unknown extension: look at the first bytes.
    char head[16] = {};
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path.string() + ": cannot open: " + std::strerror(errno));
    in.read(head, sizeof head);
    const std::string_view h(head, static_cast<std::size_t>(in.gcount()));
    if (h.empty()) throw Error(path.string() + ": file is empty");
    if (h.substr(0, 4) == "ply\n" || h.substr(0, 5) == "ply\r\n") return Format::ply;
    if (h.substr(0, 6) == "# .PCD" || h.substr(0, 7) == "VERSION") return Format::pcd;
    throw Error(path.string() + ": unknown format (extension '" + ext +
                "' and content not recognised); name it with --format ply|pcd|xyz|mesh");
}

std::vector<std::string> Report::summary_lines() const {
    std::vector<std::string> lines;
    lines.push_back("read " + reader + ": " + std::to_string(records) + " points in " +
                    fmt("%.3f s", read_seconds));
    for (const std::string& n : notes) lines.push_back(n);
    if (nan_entries)
        lines.push_back("dropped " + std::to_string(nan_entries) +
                        " entries with NaN coordinates (holes of an organized cloud)");
    if (faces)
        lines.push_back(
            "mesh: " + std::to_string(faces) + " faces" +
            (faces_invalid ? ", " + std::to_string(faces_invalid) + " invalid faces skipped" : "") +
            (unreferenced_vertices ? ", " + std::to_string(unreferenced_vertices) + " vertices on no face"
                                   : "") +
            (cancelled_normals ? ", " + std::to_string(cancelled_normals) +
                                     " vertices whose face normals cancel (double-sided faces)"
                               : "") +
            (fallback_normals
                 ? ", " + std::to_string(fallback_normals) + " vertices took the normal from the other source"
                 : ""));
    lines.push_back("clean: " + clean.summary());
    if (!normals_detail.empty()) lines.push_back("normals: " + normals_detail);
    return lines;
}

std::string options_json(const std::filesystem::path& input, const Options& options) {
    nlohmann::json j;
    j["input"] = input.string();
    j["format"] = format_name(options.format);
    j["normals"] = normals_name(options.normals);
    j["mesh_mode"] = mesh_mode_name(options.mesh_mode);
    j["sample"] = options.sample;
    j["seed"] = options.seed;
    j["sample_normals"] = options.sample_normals == SampleNormals::face ? "face" : "interpolated";
    j["k"] = options.k;
    if (options.sensor)
        j["sensor"] = {(*options.sensor)[0], (*options.sensor)[1], (*options.sensor)[2]};
    else
        j["sensor"] = nullptr;
    j["keep_duplicates"] = options.keep_duplicates;
    return j.dump();
}

PointCloud import_file(const std::filesystem::path& path, const Options& options, Report& report) {
    const std::string label = path.string();
    const bool quiet = options.quiet;
    const double t0 = tool::now_seconds();
    Format format = options.format == Format::automatic ? detect_format(path) : options.format;

    // A PLY with faces: a mesh or a point set (MeshMode).
    if (format == Format::ply && options.mesh_mode != MeshMode::points) {
        if (options.mesh_mode == MeshMode::mesh || options.sample > 0) {
            format = Format::mesh;
        } else {
            const MappedFile file = MappedFile::open(path);
            const PlyHeader header = parse_ply_header(file.view(), label);
            if (header.face_count() > 0 && !header.has_vertex_normals()) {
                if (have_openmesh())
                    format = Format::mesh;
                else
                    report.notes.push_back(label +
                                           ": has faces but this build lacks OpenMesh: its vertices are read "
                                           "as points");
            }
        }
    }
    if (options.sample > 0 && format != Format::mesh)
        throw Error(label +
                    ": --sample needs a mesh (OBJ/OFF/STL, or a PLY with faces without --mesh-mode points)");

    PointCloud cloud;
    bool mesh_normals = false;
    switch (format) {
        case Format::ply:
            cloud = read_ply(path, report, quiet);
            break;
        case Format::xyz:
            cloud = read_xyz(path, report, quiet);
            break;
        case Format::pcd:
            cloud = read_pcd(path, report, quiet);
            break;
        case Format::mesh: {
            precheck_mesh_file(path);
            const MeshData mesh = read_mesh(path, report, quiet);
            if (options.sample > 0) {
                try {
                    cloud = sample_mesh(mesh, options.sample, options.seed, options.sample_normals);
                } catch (const Error& e) {
                    throw Error(label + ": " + e.what());  // the one error that cannot name the file
                }
                report.records = cloud.size();
                report.normals_detail =
                    options.sample_normals == SampleNormals::face
                        ? "face normals of the sampled faces"
                        : "area-weighted vertex normals interpolated over the sampled faces";
                report.reader += ", " + std::to_string(options.sample) + " samples (seed " +
                                 std::to_string(options.seed) + ")";
            } else {
                cloud = mesh_vertices(mesh, options.normals == NormalsMode::keep, report);
                report.records = cloud.size();
                if (options.normals == NormalsMode::keep)
                    report.normals_detail = report.normals_area_weighted
                                                ? "the file's vertex normals, area-weighted where it has none"
                                                : "the file's vertex normals";
                else
                    report.normals_detail =
                        report.normals_from_file
                            ? "area-weighted vertex normals (sum of face normals weighted by "
                              "face area), the file's where the faces give none"
                            : "area-weighted vertex normals (sum of face normals weighted by "
                              "face area)";
            }
            mesh_normals = true;
            break;
        }
        case Format::automatic:
            break;
    }
    report.read_seconds = tool::now_seconds() - t0;
    if (!mesh_normals && cloud.has_normals()) {
        report.normals_from_file = true;
        report.normals_detail = "from the file";
    }
    if (options.normals == NormalsMode::estimate && cloud.has_normals()) {
        cloud.normals.clear();
        report.normals_from_file = false;
        report.normals_area_weighted = false;
    }

    report.clean = clean(cloud, !options.keep_duplicates);
    if (cloud.size() == 0) throw Error(label + ": no points left: " + report.clean.summary());

    if (!cloud.has_normals() && options.normals != NormalsMode::keep) {
        const double t1 = tool::now_seconds();
        std::vector<pool::Float3> normals;
        KnnGraph graph;
        try {
            estimate_normals(cloud, options.k, normals, options.sensor ? nullptr : &graph, quiet);
        } catch (const Error& e) {
            throw Error(label + ": " + e.what());
        }
        OrientStats stats;
        std::string how;
        if (options.sensor) {
            const auto& s = *options.sensor;
            stats = orient_toward(cloud.positions, normals, s);
            report.oriented_to_sensor = true;
            how = "oriented toward the sensor at (" + fmt("%g", s[0]) + ", " + fmt("%g", s[1]) + ", " +
                  fmt("%g", s[2]) + "); " + std::to_string(stats.ambiguous) +
                  " ambiguous (normal more than 84 degrees from the line of sight)";
        } else {
            stats = orient_by_propagation(cloud.positions, normals, graph, quiet);
            how = "oriented by propagation over the k-NN graph (Hoppe 1992): " +
                  std::to_string(stats.components) +
                  " components, each seeded at its highest point with +z outward; " +
                  std::to_string(stats.ambiguous) +
                  " ambiguous (|n_i . n_j| < 0.1 to every neighbour oriented before)";
        }
        report.components = stats.components;
        report.ambiguous = stats.ambiguous;
        cloud.normals = std::move(normals);
        cloud.flags |= pool::k_model_normals_estimated;
        report.normals_estimated = true;
        // PCA fails on degenerate neighbourhoods (fewer than 3 distinct points): those have no normal.
        const CleanReport second = clean(cloud, false);
        report.estimate_failed = second.zero_normal;
        report.normals_seconds = tool::now_seconds() - t1;
        report.normals_detail =
            "estimated by PCA over k=" + std::to_string(options.k) + " neighbours in " +
            fmt("%.3f s", report.normals_seconds) + "; " + how +
            (report.estimate_failed ? "; " + std::to_string(report.estimate_failed) +
                                          " points without a normal (degenerate neighbourhood) dropped"
                                    : "");
        if (cloud.size() == 0) throw Error(label + ": no points left after normal estimation");
    } else if (!cloud.has_normals()) {
        report.normals_detail =
            "none (the file has none and --normals keep): the pool has no normals section";
    }
    report.written = cloud.size();
    return cloud;
}

}  // namespace prt::pre::import
