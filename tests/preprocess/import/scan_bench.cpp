// prt-bench-scans: the measurements behind prt-import's defaults for real scans (issue 15).
//   outliers: per model, the share of good points each outlier setting removes (real scans where
//             no outliers are expected at that level) and the share of synthetic outliers it
//             removes (1 % of the points moved along the line of sight by 5-25 % of the model size);
//   normals:  the ten bunny scans merged with bun.conf: the share of estimated normals that agree
//             in sign with bun_zipper.ply's area-weighted normal at the nearest vertex, oriented
//             toward each scan's sensor, with grazing normals from their neighbours, or by
//             propagation alone;
//   time:     outlier removal (one k-NN pass) on N points.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "import.h"
#include "neighbours.h"
#include "prt/tool.h"
#include "scan_reference.h"

namespace fs = std::filesystem;
namespace imp = prt::pre::import;
using prt_scan_ref::Vec3;

namespace {

struct Model {
    std::string name;
    std::vector<std::vector<Vec3>> scans;  ///< outlier removal runs per scan
    std::vector<prt::pool::Sensor> sensors;
};

std::vector<Vec3> load(const fs::path& p, prt::pool::Sensor* sensor = nullptr) {
    imp::Options o;
    o.outliers.enabled = false;
    o.normals = imp::NormalsMode::keep;
    o.quiet = true;
    imp::Report r;
    auto c = imp::import_file(p, o, r);
    if (sensor && !c.sensors.empty()) *sensor = c.sensors[0];
    return c.positions;
}

std::vector<Model> models(const fs::path& data) {
    std::vector<Model> out;
    const fs::path bunny = data / "points/stanford_bunny/data";
    const prt::pool::Sensor up{{0, 0, 1}, prt::pool::k_sensor_direction, 0};
    if (fs::exists(bunny / "bun000.ply")) {
        out.push_back({"bun000", {load(bunny / "bun000.ply")}, {up}});
        Model merged{"bunny 10 scans", {}, {}};
        for (const char* s : {"bun000", "bun045", "bun090", "bun180", "bun270", "bun315", "chin", "ear_back",
                              "top2", "top3"}) {
            merged.scans.push_back(load(bunny / (std::string(s) + ".ply")));
            merged.sensors.push_back(up);  // each scan's own frame: the scanner along +z
        }
        out.push_back(std::move(merged));
    }
    if (fs::exists(data / "points/cgal_kitten/kitten.xyz"))
        out.push_back({"kitten", {load(data / "points/cgal_kitten/kitten.xyz")}, {up}});
    if (fs::exists(data / "points/stanford_dragon/dragon_small.obj"))
        out.push_back({"dragon vertices", {load(data / "points/stanford_dragon/dragon_small.obj")}, {up}});
    if (fs::exists(data / "points/stanford_armadillo/armadillo.off"))
        out.push_back({"armadillo vertices", {load(data / "points/stanford_armadillo/armadillo.off")}, {up}});
    const fs::path mug = data / "points/pcl/table_scene_mug_stereo_textured.pcd";
    if (fs::exists(mug) && imp::have_pcl()) {
        prt::pool::Sensor s{{0, 0, 0}, prt::pool::k_sensor_point, 0};
        auto pts = load(mug, &s);
        out.push_back({"mug scene (PCD)", {std::move(pts)}, {s}});
    }
    // Synthetic: a sphere and a plane sampled at random, seen from a sensor.
    {
        std::mt19937_64 rng(5);
        std::normal_distribution<double> g(0, 1);
        std::vector<Vec3> sphere;
        while (sphere.size() < 50000) {
            Vec3 v{g(rng), g(rng), g(rng)};
            const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            const Vec3 p{v[0] / l, v[1] / l, v[2] / l};
            if (p[0] * 0 + p[1] * 0 + p[2] * (5 - p[2]) - (p[0] * p[0] + p[1] * p[1]) > 0)  // n . (s - p) > 0
                sphere.push_back(p);
        }
        out.push_back({"sphere (random)", {sphere}, {{{0, 0, 5}, prt::pool::k_sensor_point, 0}}});
        std::uniform_real_distribution<double> u(-1, 1);
        std::vector<Vec3> plane, grid;
        for (int i = 0; i < 50000; ++i) plane.push_back({u(rng), u(rng), 0});
        out.push_back({"plane (random)", {plane}, {{{0.2, 0.1, 3}, prt::pool::k_sensor_point, 0}}});
        for (int i = 0; i < 200; ++i)
            for (int j = 0; j < 200; ++j) grid.push_back({i * 0.01, j * 0.01, 0});
        out.push_back({"plane (grid)", {grid}, {{{1, 1, 3}, prt::pool::k_sensor_point, 0}}});
    }
    return out;
}

struct Rates {
    double good = 0;      ///< % of good points removed
    double outliers = 0;  ///< % of synthetic outliers removed
    double far = 0;       ///< % of those removed that lie more than 3 median spacings from every scan point
};

/// Runs outlier removal per scan with `p`: on the scans as they are (good) and with 1 % outliers.
Rates rates(const Model& m, const imp::OutlierParams& p) {
    std::uint64_t good_in = 0, good_out = 0, bad_in = 0, bad_out = 0, clean_in = 0, clean_removed = 0;
    std::uint64_t far_in = 0, far_removed = 0;
    for (std::size_t s = 0; s < m.scans.size(); ++s) {
        {
            prt::pre::PointCloud c;
            c.positions = m.scans[s];
            imp::OutlierReport r;
            imp::outliers_and_graph(c, p, 0, nullptr, r, true);
            clean_in += m.scans[s].size();
            clean_removed += m.scans[s].size() - c.size();
        }
        std::vector<Vec3> pts = m.scans[s];
        const auto moved = prt_scan_ref::displace_outliers(pts, m.sensors[s],
                                                           prt_scan_ref::diagonal(m.scans[s]), 0.01, 17 + s);
        prt::pre::PointCloud c;
        c.positions = pts;
        c.intensities.resize(pts.size());
        for (std::size_t i = 0; i < pts.size(); ++i) c.intensities[i] = moved[i];
        imp::OutlierReport r;
        imp::outliers_and_graph(c, p, 0, nullptr, r, true);
        for (const std::uint8_t f : moved) (f ? bad_in : good_in) += 1;
        for (const float f : c.intensities) (f > 0 ? bad_out : good_out) += 1;
        // Outliers that left the surface: farther than 3 median spacings from every original point
        // (a point moved along the surface, near a silhouette, stays on it and is no outlier).
        const prt_scan_ref::GridNearest near(m.scans[s]);
        std::vector<double> spacing;
        for (std::size_t i = 0; i < m.scans[s].size(); i += 97) {
            const Vec3 q = m.scans[s][i];
            // nearest other point: search a point nudged off, then take the true distance
            double best = 1e300;
            for (std::size_t j = i + 1; j < std::min(m.scans[s].size(), i + 2000); ++j) {
                const double d = (m.scans[s][j][0] - q[0]) * (m.scans[s][j][0] - q[0]) +
                                 (m.scans[s][j][1] - q[1]) * (m.scans[s][j][1] - q[1]) +
                                 (m.scans[s][j][2] - q[2]) * (m.scans[s][j][2] - q[2]);
                if (d > 0) best = std::min(best, d);
            }
            spacing.push_back(std::sqrt(best));
        }
        std::nth_element(spacing.begin(), spacing.begin() + spacing.size() / 2, spacing.end());
        const double far_limit = 3.0 * spacing[spacing.size() / 2];
        std::vector<std::uint8_t> kept_flag(pts.size(), 0);
        {
            // which moved points survived: match the survivors by position
            prt::pre::PointCloud all;
            all.positions = pts;
            const prt_scan_ref::GridNearest survivors(c.positions);
            for (std::size_t i = 0; i < pts.size(); ++i)
                if (moved[i]) kept_flag[i] = survivors.nearest(pts[i]).second == 0.0;
        }
        for (std::size_t i = 0; i < pts.size(); ++i) {
            if (!moved[i] || near.nearest(pts[i]).second <= far_limit) continue;
            ++far_in;
            far_removed += !kept_flag[i];
        }
    }
    (void)good_in;
    (void)good_out;
    return {100.0 * double(clean_removed) / double(clean_in),
            100.0 * double(bad_in - bad_out) / double(bad_in),
            far_in ? 100.0 * double(far_removed) / double(far_in) : 100.0};
}

void outlier_tables(const std::vector<Model>& ms, bool grid) {
    std::printf(
        "# outlier removal per model: %% of good points removed (clean scans) / %% of synthetic\n"
        "# outliers removed / %% removed of those more than 3 median spacings from every scan point\n");
    std::printf("%-40s", "setting");
    for (const Model& m : ms) std::printf(" %22.22s", m.name.c_str());
    std::printf("\n");
    auto row = [&](const std::string& label, const imp::OutlierParams& p) {
        std::printf("%-40s", label.c_str());
        for (const Model& m : ms) {
            const Rates r = rates(m, p);
            std::printf("  %6.3f/%6.2f/%6.2f", r.good, r.outliers, r.far);
        }
        std::printf("\n");
        std::fflush(stdout);
    };
    imp::OutlierParams def;
    char l[96];
    std::snprintf(l, sizeof l, "default (k=%u std=%g radius=%g min=%u)", def.k, def.std_ratio,
                  def.radius_factor, def.min_neighbours);
    row(l, def);
    if (!grid) return;
    for (std::uint32_t k : {8u, 16u})
        for (double a : {3.0, 6.0, 8.0, 10.0}) {
            imp::OutlierParams p = def;
            p.k = k;
            p.std_ratio = a;
            p.radius_factor = 0;
            std::snprintf(l, sizeof l, "statistical k=%u std=%g", k, a);
            row(l, p);
        }
    for (std::uint32_t k : {8u, 16u})
        for (double f : {2.0, 3.0, 4.0})
            for (std::uint32_t mn : {1u, 2u, 3u}) {
                imp::OutlierParams p = def;
                p.k = k;
                p.std_ratio = 0;
                p.radius_factor = f;
                p.min_neighbours = mn;
                std::snprintf(l, sizeof l, "radius k=%u factor=%g min=%u", k, f, mn);
                row(l, p);
            }
}

/// Clumps of outliers (a point moved along its line of sight by 5-25 % of the model size and
/// c - 1 companions within a small fraction of the spacing of it), 1 % of the points in all: the
/// radius test needs `min_neighbours` companions to miss them, the statistical test does not.
void clump_table(const std::vector<Model>& ms) {
    std::printf(
        "# clumps of c outliers, 1 %% of the points: %% removed by the default / radius test alone\n");
    for (const Model& m : ms) {
        if (m.name != "bun000" && m.name.rfind("mug", 0) != 0) continue;
        const std::vector<Vec3>& base = m.scans[0];
        const double diag = prt_scan_ref::diagonal(base);
        std::printf("%-20s", m.name.c_str());
        for (const int clump : {1, 2, 3, 4, 6}) {
            std::mt19937_64 rng(4);
            std::uniform_real_distribution<double> u(0, 1);
            prt::pre::PointCloud c;
            c.positions = base;
            c.intensities.assign(c.size(), 0.f);
            std::size_t bad = 0;
            for (std::size_t i = 0; i < base.size(); ++i) {
                if (u(rng) >= 0.01 / clump) continue;
                Vec3 p = c.positions[i];
                const prt::pool::Sensor& s = m.sensors[0];
                Vec3 d;
                for (int a = 0; a < 3; ++a)
                    d[a] = s.kind == prt::pool::k_sensor_direction ? s.position[a] : p[a] - s.position[a];
                const double l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                const double shift = (0.05 + 0.2 * u(rng)) * diag * (u(rng) < 0.5 ? -1 : 1);
                for (int a = 0; a < 3; ++a) p[a] += d[a] / l * shift;
                c.positions[i] = p;
                c.intensities[i] = 1;
                ++bad;
                for (int k = 1; k < clump; ++k) {
                    Vec3 q = p;
                    for (int a = 0; a < 3; ++a) q[a] += (u(rng) - 0.5) * 5e-4 * diag;
                    c.positions.push_back(q);
                    c.intensities.push_back(1.f);
                    ++bad;
                }
            }
            double rate[2];
            for (int mode = 0; mode < 2; ++mode) {
                prt::pre::PointCloud cc = c;
                imp::OutlierParams p;
                if (mode == 1) p.std_ratio = 0;
                imp::OutlierReport r;
                imp::outliers_and_graph(cc, p, 0, nullptr, r, true);
                std::size_t left = 0;
                for (const float f : cc.intensities) left += f > 0;
                rate[mode] = 100.0 * double(bad - left) / double(bad);
            }
            std::printf("  c=%d %6.2f / %6.2f", clump, rate[0], rate[1]);
        }
        std::printf("\n");
    }
}

/// The orientation settings compared.
std::vector<std::pair<std::string, imp::Options>> settings() {
    std::vector<std::pair<std::string, imp::Options>> out;
    imp::Options o;
    o.grazing_cos = 0;
    out.push_back({"every sign from the sensor", o});
    for (double c : {0.1, 0.3, 0.5, 0.7, 0.9}) {
        imp::Options g;
        g.grazing_cos = c;
        char l[96];
        std::snprintf(l, sizeof l, "sensor, |cos| < %.1f from neighbours%s", c,
                      c == imp::Options{}.grazing_cos ? " (default)" : "");
        out.push_back({l, g});
    }
    imp::Options v;
    v.propagate_then_vote = true;
    out.push_back({"propagation, components turned to the sensors", v});
    imp::Options p;
    p.no_sensor = true;
    out.push_back({"propagation alone (--no-sensor)", p});
    return out;
}

void normals_table(const fs::path& data) {
    const fs::path conf = data / "points/stanford_bunny/data/bun.conf";
    const fs::path mesh = data / "points/stanford_bunny/reconstruction/bun_zipper.ply";
    if (!fs::exists(conf) || !fs::exists(mesh)) {
        std::printf("# normals: bunny data absent\n");
        return;
    }
    const prt_scan_ref::RefMesh ref = prt_scan_ref::read_ascii_ply_mesh(mesh.string());
    const prt_scan_ref::GridNearest nearest(ref.vertices);
    std::vector<std::vector<std::uint32_t>> around(ref.vertices.size());
    for (std::uint32_t t = 0; t < ref.triangles.size(); ++t)
        for (const std::uint32_t v : ref.triangles[t]) around[v].push_back(t);
    std::printf(
        "# bunny scans merged with bun.conf: %% of estimated normals agreeing in sign with bun_zipper.ply:\n"
        "# 'vertex': the area-weighted normal of the nearest vertex, every point; 'face': the closest\n"
        "# face around the nearest vertex, points within 0.5 mm of the mesh (it is open underneath)\n");
    std::printf("%-46s %9s %9s %9s %9s %8s %8s\n", "orientation", "points", "vertex %", "face %", "grazing",
                "flipped", "seconds");
    auto run = [&](const std::string& label, const imp::Options& base, const std::vector<fs::path>& only) {
        imp::Options o = base;
        o.quiet = true;
        imp::Report r;
        const double t0 = prt::tool::now_seconds();
        const auto c = imp::import_merged(conf, only, o, r);
        const double t = prt::tool::now_seconds() - t0;
        std::uint64_t agree = 0, counted = 0, near_agree = 0, near_counted = 0;
        for (std::size_t i = 0; i < c.size(); ++i) {
            const auto [v, d] = nearest.nearest(c.positions[i]);
            const auto& n = ref.normals[v];
            const double dn = n[0] * c.normals[i].x + n[1] * c.normals[i].y + n[2] * c.normals[i].z;
            if (!(n[0] == 0 && n[1] == 0 && n[2] == 0)) {
                ++counted;
                agree += dn > 0;
            }
            double best = 1e300;
            Vec3 fn{0, 0, 0};
            for (const std::uint32_t tri : around[v]) {
                const auto& T = ref.triangles[tri];
                const Vec3 &a = ref.vertices[T[0]], &b = ref.vertices[T[1]], &cc = ref.vertices[T[2]];
                const double dd = prt_scan_ref::point_triangle(c.positions[i], a, b, cc);
                if (dd < best) {
                    best = dd;
                    const Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]},
                        w{cc[0] - a[0], cc[1] - a[1], cc[2] - a[2]};
                    fn = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
                }
            }
            if (best > 0.0005) continue;
            ++near_counted;
            near_agree += fn[0] * c.normals[i].x + fn[1] * c.normals[i].y + fn[2] * c.normals[i].z > 0;
        }
        std::printf("%-46s %9llu %9.3f %9.4f %9llu %8llu %8.2f\n", label.c_str(),
                    static_cast<unsigned long long>(counted), 100.0 * double(agree) / double(counted),
                    100.0 * double(near_agree) / double(near_counted),
                    static_cast<unsigned long long>(r.ambiguous),
                    static_cast<unsigned long long>(r.grazing_flipped), t);
        std::fflush(stdout);
    };
    const fs::path dir = conf.parent_path();
    const std::vector<std::pair<std::string, std::vector<fs::path>>> sets = {
        {"10 scans", {}}, {"bun000 alone", {dir / "bun000.ply"}}, {"top2 alone", {dir / "top2.ply"}}};
    for (const auto& [set_name, only] : sets) {
        std::printf("## %s\n", set_name.c_str());
        for (const auto& [label, o] : settings()) run(label, o, only);
    }

    // A single view with an exact sensor: every visible surface faces the camera.
    const fs::path mug = data / "points/pcl/table_scene_mug_stereo_textured.pcd";
    if (!fs::exists(mug) || !imp::have_pcl()) return;
    std::printf(
        "# PCL mug scene (one stereo view, sensor = the PCD VIEWPOINT at the origin): %% of normals\n"
        "# facing the camera, all and where |cos| to the line of sight > 0.3\n");
    for (const auto& [label, base] : settings()) {
        imp::Options o = base;
        o.quiet = true;
        imp::Report r;
        const auto c = imp::import_file(mug, o, r);
        std::size_t face = 0, strong = 0, strong_face = 0;
        for (std::size_t i = 0; i < c.size(); ++i) {
            const auto& p = c.positions[i];
            const double l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            const double cs = -(c.normals[i].x * p[0] + c.normals[i].y * p[1] + c.normals[i].z * p[2]) / l;
            face += cs > 0;
            if (std::fabs(cs) > 0.3) {
                ++strong;
                strong_face += cs > 0;
            }
        }
        std::printf("%-46s %9zu %9.3f %9.3f\n", label.c_str(), c.size(),
                    100.0 * double(face) / double(c.size()), 100.0 * double(strong_face) / double(strong));
    }
}

void timing(std::uint64_t n) {
    // A wavy surface sampled at random (as a scan) and points uniform in a cube (bench-import's file).
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int kind = 0; kind < 2; ++kind) {
        prt::pre::PointCloud c;
        c.positions.resize(n);
        for (auto& p : c.positions) {
            p = {u(rng), u(rng), u(rng)};
            if (kind == 0) p[2] = 0.1 * std::sin(3 * p[0]) * std::cos(2 * p[1]);
        }
        for (bool graph : {false, true}) {
            prt::pre::PointCloud copy = c;
            imp::OutlierParams p;
            imp::OutlierReport r;
            imp::KnnGraph g;
            const double t0 = prt::tool::now_seconds();
            imp::outliers_and_graph(copy, p, graph ? 16 : 0, graph ? &g : nullptr, r, true);
            const double t = prt::tool::now_seconds() - t0;
            std::printf("%s, %llu points: outlier removal%s %.3f s (removed %llu)\n",
                        kind == 0 ? "surface" : "cube volume", static_cast<unsigned long long>(n),
                        graph ? " + k=16 graph for normals" : "", t,
                        static_cast<unsigned long long>(r.removed));
            std::fflush(stdout);
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    std::string data = PRT_SHARED_DATA_DIR;
    bool outliers = false, normals = false, grid = false;
    std::uint64_t time_points = 0;
    return prt::tool::run(
        argc, argv, "prt-bench-scans", "Measurements behind prt-import's outlier and orientation defaults",
        [&](CLI::App& app, prt::tool::CommonOptions&) {
            app.add_option("--data", data, "The shared data folder");
            app.add_flag("--outliers", outliers, "The default outlier setting per model");
            app.add_flag("--grid", grid, "With --outliers: a grid of settings");
            app.add_flag("--normals", normals, "Bunny normal orientation agreement");
            app.add_option("--time", time_points, "Time outlier removal on this many points (0: no)");
        },
        [&](const prt::tool::CommonOptions&) {
            std::printf("# machine: %u hardware threads\n", std::thread::hardware_concurrency());
            if (outliers) {
                const auto ms = models(data);
                outlier_tables(ms, grid);
                clump_table(ms);
            }
            if (normals) normals_table(data);
            if (time_points) timing(time_points);
        });
}
