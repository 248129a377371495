#include "import.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "mesh.h"
#include "orient.h"
#include "out_of_core.h"
#include "pcl_backend.h"
#include "ply_reader.h"
#include "poses.h"
#include "prt/error.h"
#include "prt/mapped_file.h"
#include "prt/tool_util.h"
#include "quote.h"
#include "xyz_reader.h"

namespace prt::pre::import {

namespace {

namespace fs = std::filesystem;

std::string lower_extension(const fs::path& path) {
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
        case Format::pool:
            return "pool";
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

std::string vec(const double* v) {
    // Appended in place: g++ 12's -Wrestrict misreads '"(" + std::string' once this is inlined.
    std::string s = "(";
    s += fmt("%g", v[0]);
    s += ", ";
    s += fmt("%g", v[1]);
    s += ", ";
    s += fmt("%g", v[2]);
    s += ")";
    return s;
}

std::string count(std::uint64_t n, const char* what) {
    return std::to_string(n) + " " + what;
}

/// One scan on its way into the result.
struct Scan {
    PointCloud cloud;
    bool mesh = false;  ///< mesh vertices or samples: no outlier removal
    Rigid pose;         ///< scan frame -> output frame
};

/// Reads one file into a point set as it is (no cleaning), with the file's sensor in
/// cloud.sensors. NormalsMode::estimate drops the file's normals here.
Scan read_scan(const fs::path& path, const Options& options, Report& report) {
    const std::string label = path.string();
    report.label = label;
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

    Scan scan;
    PointCloud& cloud = scan.cloud;
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
        case Format::pool: {
            const pool::PoolFile file = pool::PoolFile::open(path);
            cloud = read_point_sections(file);
            cloud.radii.clear();  // stale once points move or go: prt-radii computes them again
            pool_input_report(file, path, report);
            break;
        }
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
            scan.mesh = true;
            break;
        }
        case Format::automatic:
            break;
    }
    report.read_seconds = tool::now_seconds() - t0;
    if (!scan.mesh && cloud.has_normals()) {
        report.normals_from_file = true;
        report.normals_detail = "from the file";
    }
    if (options.normals == NormalsMode::estimate && cloud.has_normals()) {
        cloud.normals.clear();
        cloud.flags &= ~static_cast<std::uint32_t>(pool::k_model_normals_estimated);
        report.normals_from_file = false;
        report.normals_area_weighted = false;
        report.normals_detail.clear();
    }
    // Intensity or colour sections of a pool may be absent; per-point arrays must be all or none.
    if (cloud.has_scan_ids() && cloud.sensors.empty()) cloud.scan_ids.clear();
    return scan;
}

/// Splits a pool holding several scans (scan_ids) into one scan per sensor, in sensor order.
std::vector<Scan> split_by_scan(Scan&& whole) {
    PointCloud& c = whole.cloud;
    const std::size_t m = c.sensors.size();
    std::vector<Scan> out(m);
    for (std::size_t s = 0; s < m; ++s) {
        out[s].mesh = whole.mesh;
        out[s].cloud.sensors = {c.sensors[s]};
        out[s].cloud.flags = c.flags;
    }
    for (std::size_t i = 0; i < c.size(); ++i) {
        PointCloud& d = out[c.scan_ids[i]].cloud;
        d.positions.push_back(c.positions[i]);
        if (c.has_normals()) d.normals.push_back(c.normals[i]);
        if (c.has_colors()) d.colors.push_back(c.colors[i]);
        if (c.has_intensities()) d.intensities.push_back(c.intensities[i]);
    }
    std::erase_if(out, [](const Scan& s) { return s.cloud.size() == 0; });
    return out;
}

/// Keeps the points whose hash of (seed, index) falls below `fraction` (a counter-based hash:
/// the same points for the same file and seed); returns how many were dropped.
std::uint64_t decimate(PointCloud& c, double fraction, std::uint64_t seed) {
    const std::size_t n = c.size();
    std::vector<std::uint8_t> keep_flags(n);
    for (std::size_t i = 0; i < n; ++i) keep_flags[i] = decimation_keeps(i, fraction, seed) ? 1 : 0;
    return n - keep_points(c, keep_flags);
}

std::string sensor_text(const pool::Sensor& s) {
    return (s.kind == pool::k_sensor_direction ? "direction " : "point ") + vec(s.position);
}

/// Clean, outliers, the pose; `graph` (single scans that need normals) receives the k-NN graph of
/// the same pass.
void prepare_scan(Scan& scan, const Options& options, Report& report, std::uint32_t graph_k,
                  KnnGraph* graph) {
    PointCloud& cloud = scan.cloud;
    if (options.keep_fraction < 1.0) report.decimated = decimate(cloud, options.keep_fraction, options.seed);
    report.clean = clean(cloud, !options.keep_duplicates);
    if (cloud.size() == 0) throw Error(report.label + ": no points left: " + report.clean.summary());
    OutlierParams params = options.outliers;
    if (scan.mesh) params.enabled = false;
    if (cloud.sensors.size() == 1 && cloud.sensors[0].kind == pool::k_sensor_point)
        params.sensor = std::array<double, 3>{cloud.sensors[0].position[0], cloud.sensors[0].position[1],
                                              cloud.sensors[0].position[2]};
    try {
        outliers_and_graph(cloud, params, graph_k, graph, report.outliers, options.quiet);
    } catch (const Error& e) {
        throw Error(report.label + ": " + e.what());
    }
    if (scan.mesh) report.outliers.skipped = "not run (a mesh: its vertices or samples lie on the surface)";
    if (cloud.size() == 0) throw Error(report.label + ": no points left after outlier removal");
    if (!scan.pose.is_identity()) {
        for (auto& p : cloud.positions) p = scan.pose.apply(p);
        for (auto& n : cloud.normals) {
            const auto r = scan.pose.rotate({n.x, n.y, n.z});
            n = {static_cast<float>(r[0]), static_cast<float>(r[1]), static_cast<float>(r[2])};
        }
        for (auto& s : cloud.sensors) s = scan.pose.apply(s);
    }
}

/// Appends `part` to `merged` (attributes that only some scans have are dropped, said in a note).
void append(PointCloud& merged, PointCloud&& part, bool first, std::vector<std::string>& dropped) {
    if (first) {
        merged = std::move(part);
        return;
    }
    const std::size_t before = merged.size(), add = part.size();
    auto join = [&](auto& into, auto& from, const char* what) {
        if (into.empty() && from.empty()) return;
        if (into.size() == before && from.size() == add) {
            into.insert(into.end(), from.begin(), from.end());
            return;
        }
        if (std::find(dropped.begin(), dropped.end(), what) == dropped.end()) dropped.push_back(what);
        into.clear();
    };
    merged.positions.insert(merged.positions.end(), part.positions.begin(), part.positions.end());
    join(merged.normals, part.normals, "normals");
    join(merged.colors, part.colors, "colors");
    join(merged.intensities, part.intensities, "intensities");
    join(merged.radii, part.radii, "radii");
    merged.flags |= part.flags;
}

/// Estimates and orients normals of the points without one (all of them unless `given` marks the
/// file's), fills the report's normal lines.
void normals_for(PointCloud& cloud, KnnGraph& graph, const std::vector<std::uint8_t>* given,
                 const Options& options, Report& report, const std::string& label) {
    const double t1 = tool::now_seconds();
    const std::uint32_t k = static_cast<std::uint32_t>(options.k);
    std::vector<pool::Float3> normals;
    try {
        if (cloud.size() < 3)
            throw Error("too few points (" + std::to_string(cloud.size()) + ") to estimate normals");
        normals = pca_normals(cloud.positions, graph, k, options.quiet);
    } catch (const Error& e) {
        throw Error(label + ": " + e.what());
    }
    std::uint64_t kept = 0;
    if (given)
        for (std::size_t i = 0; i < cloud.size(); ++i)
            if ((*given)[i]) {
                normals[i] = cloud.normals[i];
                ++kept;
            }
    std::vector<std::uint8_t> estimated(cloud.size(), 1);
    if (given)
        for (std::size_t i = 0; i < cloud.size(); ++i) estimated[i] = !(*given)[i];
    OrientStats stats;
    std::string how;
    auto line_of_sight = [&](std::size_t i) {
        const pool::Sensor& sn = cloud.sensors[cloud.scan_ids.empty() ? 0 : cloud.scan_ids[i]];
        double d[3];
        for (int a = 0; a < 3; ++a)
            d[a] =
                sn.kind == pool::k_sensor_direction ? sn.position[a] : sn.position[a] - cloud.positions[i][a];
        const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        return std::array<double, 3>{d[0] / len, d[1] / len, d[2] / len};
    };
    if (!cloud.sensors.empty() && options.propagate_then_vote) {
        std::vector<std::uint32_t> component;
        stats = orient_by_propagation(cloud.positions, normals, graph, options.quiet,
                                      kept > 0 ? given : nullptr, &component);
        std::vector<double> vote(stats.components + 1, 0.0);
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            if (!estimated[i] || !std::isfinite(normals[i].x)) continue;
            const auto d = line_of_sight(i);
            const double c = normals[i].x * d[0] + normals[i].y * d[1] + normals[i].z * d[2];
            if (std::isfinite(c)) vote[component[i]] += c;
        }
        std::uint64_t turned = 0;
        for (std::size_t i = 0; i < cloud.size(); ++i)
            if (estimated[i] && component[i] > 0 && vote[component[i]] < 0) {
                normals[i] = {-normals[i].x, -normals[i].y, -normals[i].z};
                ++turned;
            }
        report.oriented_to_sensor = true;
        how = "oriented by propagation over the k-NN graph (Hoppe 1992), " +
              std::to_string(stats.components) +
              " components each turned to face its sensors on the whole (" + std::to_string(turned) +
              " normals turned); " + std::to_string(stats.ambiguous) + " ambiguous";
    } else if (!cloud.sensors.empty()) {
        std::vector<std::uint8_t> grazing;
        stats = orient_toward(cloud.positions, normals, cloud.sensors, cloud.scan_ids, &grazing, &estimated);
        report.oriented_to_sensor = true;
        how =
            (cloud.sensors.size() == 1 ? "oriented toward the sensor (" + sensor_text(cloud.sensors[0]) + ")"
                                       : "oriented toward each point's own sensor (" +
                                             std::to_string(cloud.sensors.size()) + " scans)") +
            "; " + std::to_string(stats.ambiguous) +
            " ambiguous (grazing: normal within 5.7 degrees of perpendicular to the line of sight)";
        if (options.grazing_cos > 0) {
            std::vector<std::uint8_t> fixed(cloud.size());
            std::uint64_t unsure = 0;
            for (std::size_t i = 0; i < cloud.size(); ++i) {
                if (!estimated[i]) {
                    fixed[i] = 1;
                    continue;
                }
                const auto d = line_of_sight(i);
                fixed[i] = std::fabs(normals[i].x * d[0] + normals[i].y * d[1] + normals[i].z * d[2]) >=
                           options.grazing_cos;
                unsure += !fixed[i];
            }
            const OrientStats p =
                unsure > 0 ? orient_by_propagation(cloud.positions, normals, graph, options.quiet, &fixed)
                           : OrientStats{};
            report.grazing_flipped = p.flipped;
            how += "; the " + std::to_string(unsure) + " more than " +
                   fmt("%.1f", std::acos(options.grazing_cos) * 180 / 3.14159265358979323846) +
                   " degrees from their line of sight took their sign from the others over the k-NN graph (" +
                   std::to_string(p.flipped) + " flipped)";
        }
    } else {
        bool any_given = kept > 0;
        stats = orient_by_propagation(cloud.positions, normals, graph, options.quiet,
                                      any_given ? given : nullptr);
        how = "oriented by propagation over the k-NN graph (Hoppe 1992): " +
              (any_given ? "from the file's normals, then " : std::string()) +
              std::to_string(stats.components) +
              " components seeded at their highest point with +z outward; " +
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
        fmt("%.3f s", report.normals_seconds) +
        (kept ? " (" + count(kept, "kept from the files") + ")" : "") + "; " + how +
        (report.estimate_failed ? "; " + std::to_string(report.estimate_failed) +
                                      " points without a normal (degenerate neighbourhood) dropped"
                                : "");
    if (cloud.size() == 0) throw Error(label + ": no points left after normal estimation");
}

/// Everything after reading: per scan clean + outliers + pose, merge, sensors, normals.
PointCloud finish(std::vector<Scan>& scans, std::vector<Report>& scan_reports, const Options& options,
                  Report& report, const std::string& label) {
    const bool single = scans.size() == 1 && scans[0].pose.is_identity();
    const std::uint32_t k = static_cast<std::uint32_t>(options.k);

    // Sensors each scan brings (--no-sensor drops them; --sensor replaces them after merging).
    for (Scan& s : scans)
        if (options.no_sensor) {
            s.cloud.sensors.clear();
            s.cloud.scan_ids.clear();
        }
    bool all_normals = true, any_normals = false;
    for (const Scan& s : scans) {
        all_normals = all_normals && s.cloud.has_normals();
        any_normals = any_normals || s.cloud.has_normals();
    }
    const bool estimate = options.normals != NormalsMode::keep && !all_normals;

    // The single-scan case shares one k-NN pass between outliers and normals.
    KnnGraph graph;
    for (std::size_t i = 0; i < scans.size(); ++i)
        prepare_scan(scans[i], options, scan_reports[i], single && estimate ? k : 0,
                     single ? &graph : nullptr);

    PointCloud cloud;
    std::vector<std::string> dropped;
    std::vector<std::uint8_t> given;  // per point: the normal came from the file
    const bool mixed_normals = any_normals && !all_normals;
    bool all_sensors = true, any_sensor = false;
    std::uint64_t sensor_total = 0;
    for (const Scan& s : scans) {
        all_sensors = all_sensors && !s.cloud.sensors.empty();
        any_sensor = any_sensor || !s.cloud.sensors.empty();
        sensor_total += s.cloud.sensors.size();
    }
    if (sensor_total > pool::k_max_sensors)
        throw Error(label + ": " + std::to_string(sensor_total) + " sensors, at most " +
                    std::to_string(pool::k_max_sensors) + " (scan_ids are 16-bit)");
    std::vector<pool::Sensor> sensors;
    std::vector<std::uint16_t> scan_ids;
    for (std::size_t i = 0; i < scans.size(); ++i) {
        PointCloud& c = scans[i].cloud;
        if (mixed_normals) given.insert(given.end(), c.size(), c.has_normals() ? 1 : 0);
        // Placeholders (unit, so clean() keeps them) for the scans without normals; `given` says which.
        if (mixed_normals && !c.has_normals()) c.normals.assign(c.size(), {0.f, 0.f, 1.f});
        if (all_sensors && !single) {
            const std::uint16_t base = static_cast<std::uint16_t>(sensors.size());
            if (c.has_scan_ids())
                for (const std::uint16_t id : c.scan_ids)
                    scan_ids.push_back(static_cast<std::uint16_t>(base + id));
            else
                scan_ids.insert(scan_ids.end(), c.size(), base);
            sensors.insert(sensors.end(), c.sensors.begin(), c.sensors.end());
        }
        c.scan_ids.clear();
        if (!single) c.sensors.clear();
        append(cloud, std::move(c), i == 0, dropped);
    }
    if (!single) {
        cloud.sensors = std::move(sensors);
        cloud.scan_ids = std::move(scan_ids);
    }
    if (any_sensor && !all_sensors)
        report.notes.push_back(
            label + ": only some scans have a sensor: none recorded, normals oriented by propagation");
    for (const std::string& d : dropped)
        if (d != "normals")
            report.notes.push_back(label + ": only some scans have " + d + ": dropped from the result");
    if (options.sensor) {
        cloud.sensors = {pool::Sensor{
            {(*options.sensor)[0], (*options.sensor)[1], (*options.sensor)[2]}, pool::k_sensor_point, 0}};
        cloud.scan_ids.clear();
    } else if (options.sensor_direction) {
        const auto& d = *options.sensor_direction;
        const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (!(len > 0) || !std::isfinite(len))
            throw Error("--sensor-direction must be a finite non-zero vector");
        cloud.sensors = {pool::Sensor{{d[0] / len, d[1] / len, d[2] / len}, pool::k_sensor_direction, 0}};
        cloud.scan_ids.clear();
    }
    if (cloud.sensors.size() == 1) cloud.scan_ids.clear();  // POOL.md: absent with one sensor

    if (!single) {
        // Merged: sums of the scans' counts, then duplicates across scans.
        for (const Report& r : scan_reports) {
            report.records += r.records;
            report.nan_entries += r.nan_entries;
            report.malformed_lines += r.malformed_lines;
            report.outliers.input += r.outliers.input;
            report.outliers.removed += r.outliers.removed;
            report.outliers.statistical += r.outliers.statistical;
            report.outliers.radius += r.outliers.radius;
            report.outliers.seconds += r.outliers.seconds;
            report.outliers.ran = report.outliers.ran || r.outliers.ran;
            report.read_seconds += r.read_seconds;
        }
        std::vector<std::size_t> kept;
        report.clean = clean(cloud, !options.keep_duplicates, mixed_normals ? &kept : nullptr);
        if (mixed_normals) {
            for (std::size_t i = 0; i < kept.size(); ++i) given[i] = given[kept[i]];
            given.resize(kept.size());
            if (options.normals != NormalsMode::keep)
                report.notes.push_back(label + ": only some scans have normals: the others' are estimated");
        }
    }

    if (mixed_normals && options.normals == NormalsMode::keep) {
        cloud.normals.clear();
        report.notes.push_back(label +
                               ": only some scans have normals and --normals keep: the result has none");
    }
    if (estimate) {
        if (!single) {
            OutlierParams none;
            none.enabled = false;
            OutlierReport unused;
            outliers_and_graph(cloud, none, k, &graph, unused, options.quiet);
        }
        normals_for(cloud, graph, mixed_normals ? &given : nullptr, options, report, label);
    } else if (!cloud.has_normals()) {
        report.normals_detail =
            "none (the file has none and --normals keep): the pool has no normals section";
    } else if (!single) {
        report.normals_detail = "from the files";
        report.normals_from_file = true;
    }

    if (cloud.sensors.empty())
        report.sensors_detail = "none";
    else if (cloud.sensors.size() == 1)
        report.sensors_detail =
            "1 " + sensor_text(cloud.sensors[0]) +
            (options.sensor || options.sensor_direction ? " (command line)"
             : !scan_reports[0].sensor_source.empty()   ? " (" + scan_reports[0].sensor_source + ")"
                                                        : std::string());
    else
        report.sensors_detail = std::to_string(cloud.sensors.size()) + " (one per scan), scan_ids per point";
    report.written = cloud.size();
    return cloud;
}

}  // namespace

void throw_missing_library(const std::filesystem::path& path, const char* what, const char* library,
                           const char* hint) {
    throw Error(path.string() + ": " + what + " needs " + library + ", and this build of prt-import has no " +
                library + " (" + hint + ")");
}

Format detect_format(const fs::path& path) {
    const std::string ext = lower_extension(path);
    if (ext == ".ply") return Format::ply;
    if (ext == ".pcd") return Format::pcd;
    if (ext == ".xyz" || ext == ".txt" || ext == ".csv") return Format::xyz;
    if (ext == ".obj" || ext == ".off" || ext == ".stl") return Format::mesh;
    if (ext == ".pool") return Format::pool;
    // Unknown extension: look at the first bytes.
    char head[16] = {};
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path.string() + ": cannot open: " + std::strerror(errno));
    in.read(head, sizeof head);
    const std::string_view h(head, static_cast<std::size_t>(in.gcount()));
    if (h.empty()) throw Error(path.string() + ": file is empty");
    if (h.substr(0, 4) == "ply\n" || h.substr(0, 5) == "ply\r\n") return Format::ply;
    if (h.substr(0, 6) == "# .PCD" || h.substr(0, 7) == "VERSION") return Format::pcd;
    if (h.substr(0, 8) == std::string_view("PRTPOOL\0", 8)) return Format::pool;
    throw Error(path.string() + ": unknown format (extension '" + ext +
                "' and content not recognised); name it with --format ply|pcd|xyz|mesh|pool");
}

std::vector<std::string> Report::summary_lines() const {
    std::vector<std::string> lines;
    auto scan_lines = [&lines](const Report& r, const std::string& prefix) {
        lines.push_back(prefix + "read " + r.reader + ": " + std::to_string(r.records) + " points in " +
                        fmt("%.3f s", r.read_seconds));
        for (const std::string& n : r.notes) lines.push_back(n);  // notes name their file
        if (r.nan_entries)
            lines.push_back(prefix + "dropped " + std::to_string(r.nan_entries) +
                            " entries with NaN coordinates (holes of an organized cloud)");
        if (r.faces)
            lines.push_back(
                prefix + "mesh: " + std::to_string(r.faces) + " faces" +
                (r.faces_invalid ? ", " + std::to_string(r.faces_invalid) + " invalid faces skipped" : "") +
                (r.unreferenced_vertices
                     ? ", " + std::to_string(r.unreferenced_vertices) + " vertices on no face"
                     : "") +
                (r.cancelled_normals ? ", " + std::to_string(r.cancelled_normals) +
                                           " vertices whose face normals cancel (double-sided faces)"
                                     : "") +
                (r.fallback_normals ? ", " + std::to_string(r.fallback_normals) +
                                          " vertices took the normal from the other source"
                                    : ""));
        if (r.decimated)
            lines.push_back(prefix + "decimated: dropped " + std::to_string(r.decimated) + " of " +
                            std::to_string(r.records) + " points (--keep-fraction)");
        lines.push_back(prefix + "clean: " + r.clean.summary());
        lines.push_back(prefix + "outliers: " + r.outliers.summary());
    };
    if (scans.empty()) {
        scan_lines(*this, "");
    } else {
        for (const Report& r : scans) scan_lines(r, r.label + ": ");
        for (const std::string& n : notes) lines.push_back(n);
        lines.push_back("merged " + std::to_string(scans.size()) + " scans: " + std::to_string(records) +
                        " points read, " + std::to_string(outliers.removed) + " outliers removed");
        lines.push_back("clean (merged): " + clean.summary());
    }
    lines.push_back("sensors: " + sensors_detail);
    if (!normals_detail.empty()) lines.push_back("normals: " + normals_detail);
    return lines;
}

std::string options_json(const std::vector<fs::path>& inputs, const fs::path& poses, const Options& options) {
    nlohmann::json j;
    if (inputs.size() == 1 && poses.empty())
        j["input"] = inputs[0].string();
    else {
        j["inputs"] = nlohmann::json::array();
        for (const auto& p : inputs) j["inputs"].push_back(p.string());
    }
    if (!poses.empty()) j["poses"] = poses.string();
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
    if (options.sensor_direction)
        j["sensor_direction"] = {(*options.sensor_direction)[0], (*options.sensor_direction)[1],
                                 (*options.sensor_direction)[2]};
    j["no_sensor"] = options.no_sensor;
    j["grazing_cos"] = options.grazing_cos;
    j["outliers"] = {{"enabled", options.outliers.enabled},
                     {"k", options.outliers.k},
                     {"std", options.outliers.std_ratio},
                     {"radius", options.outliers.radius_factor},
                     {"min_neighbours", options.outliers.min_neighbours}};
    j["keep_duplicates"] = options.keep_duplicates;
    j["keep_fraction"] = options.keep_fraction;
    return j.dump();
}

PointCloud import_file(const fs::path& path, const Options& options, Report& report) {
    std::vector<Scan> scans;
    scans.push_back(read_scan(path, options, report));
    const std::string label = path.string();
    if (scans[0].cloud.sensors.size() > 1 && scans[0].cloud.has_scan_ids()) {
        // A pool of several scans: filtered scan by scan, as a merged import.
        Report whole = report;
        scans = split_by_scan(std::move(scans[0]));
        std::vector<Report> per(scans.size());
        for (std::size_t i = 0; i < scans.size(); ++i) {
            per[i].label = label + " scan " + std::to_string(i);
            per[i].reader = whole.reader;
            per[i].records = scans[i].cloud.size();
            per[i].sensor_source = whole.sensor_source;
        }
        report.records = 0;
        report.read_seconds = 0;
        PointCloud cloud = finish(scans, per, options, report, label);
        report.scans = std::move(per);
        return cloud;
    }
    std::vector<Report> per(1);
    // The single scan's report is the import's report itself.
    per[0] = std::move(report);
    PointCloud cloud;
    try {
        cloud = finish(scans, per, options, per[0], label);
    } catch (...) {
        report = std::move(per[0]);
        throw;
    }
    report = std::move(per[0]);
    return cloud;
}

PointCloud import_merged(const fs::path& poses, const std::vector<fs::path>& only, const Options& options,
                         Report& report) {
    std::vector<PoseEntry> entries = read_poses(poses, only);
    std::vector<Scan> scans;
    std::vector<Report> per;  // one per scan, in step with `scans`
    for (const PoseEntry& entry : entries) {
        Report r;
        Scan s = read_scan(entry.file, options, r);
        if (entry.sensor_given) {
            s.cloud.sensors.clear();
            s.cloud.scan_ids.clear();
            if (entry.sensor) s.cloud.sensors.push_back(*entry.sensor);
            r.sensor_source = entry.where;
        }
        if (s.cloud.sensors.size() > 1 && s.cloud.has_scan_ids()) {
            // A multi-scan pool inside a pose list: its scans stay apart.
            std::vector<Scan> parts = split_by_scan(std::move(s));
            for (std::size_t p = 0; p < parts.size(); ++p) {
                parts[p].pose = entry.pose;
                Report part = r;
                part.label = r.label + " scan " + std::to_string(p);
                part.records = parts[p].cloud.size();
                if (p > 0) part.pools.clear();
                per.push_back(std::move(part));
                scans.push_back(std::move(parts[p]));
            }
            continue;
        }
        s.pose = entry.pose;
        scans.push_back(std::move(s));
        per.push_back(std::move(r));
    }
    for (const Report& r : per) report.pools.insert(report.pools.end(), r.pools.begin(), r.pools.end());
    report.reader = "pose list " + poses.string();
    PointCloud cloud = finish(scans, per, options, report, poses.string());
    report.scans = std::move(per);
    return cloud;
}

}  // namespace prt::pre::import
