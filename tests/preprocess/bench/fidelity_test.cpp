// The fidelity measure of issue 15: its independent references (triangle BVH, exact k-d tree) against
// analytic answers and brute force, and prt-fidelity end to end on a sphere with a planted hole and
// planted floating points, where the expected counts are known.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "../../runtime/tool_run.h"
#include "mesh_reference.h"
#include "point_cloud.h"
#include "point_spacing.h"
#include "prt/formats/pool.h"

namespace fs = std::filesystem;
using prt::bench::D3;

namespace {

fs::path temp_dir(const std::string& name) {
    const fs::path d =
        fs::temp_directory_path() / ("prt_fidelity_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

/// A UV sphere of radius r: (stacks + 1) x slices vertices, outward winding unless `inward`.
void uv_sphere(double r, int stacks, int slices, bool inward, std::vector<D3>& v,
               std::vector<std::array<std::uint32_t, 3>>& t) {
    v.clear();
    t.clear();
    for (int i = 0; i <= stacks; ++i) {
        const double th = M_PI * i / stacks;
        for (int j = 0; j < slices; ++j) {
            const double ph = 2 * M_PI * j / slices;
            v.push_back({r * std::sin(th) * std::cos(ph), r * std::cos(th), r * std::sin(th) * std::sin(ph)});
        }
    }
    auto id = [&](int i, int j) { return std::uint32_t(i * slices + (j % slices)); };
    for (int i = 0; i < stacks; ++i)
        for (int j = 0; j < slices; ++j) {
            // outward: (i,j) (i,j+1) (i+1,j) seen from outside is counter-clockwise
            std::array<std::uint32_t, 3> a{id(i, j), id(i, j + 1), id(i + 1, j)};
            std::array<std::uint32_t, 3> b{id(i, j + 1), id(i + 1, j + 1), id(i + 1, j)};
            if (inward) std::swap(a[1], a[2]), std::swap(b[1], b[2]);
            t.push_back(a);
            t.push_back(b);
        }
}

double len(const D3& a) {
    return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}

}  // namespace

TEST(MeshReference, RayHitsAndDistancesOfATessellatedSphere) {
    for (bool inward : {false, true}) {
        std::vector<D3> v;
        std::vector<std::array<std::uint32_t, 3>> t;
        uv_sphere(1.0, 64, 128, inward, v, t);
        const prt::bench::MeshReference mesh(v, t);
        EXPECT_EQ(mesh.flipped(), inward);
        // The facets lie inside the sphere by at most the sagitta of the longest edge.
        const double sag = 1 - std::cos(M_PI / 64);
        std::mt19937 rng(3);
        std::uniform_real_distribution<double> u(-1, 1);
        int hits = 0;
        for (int k = 0; k < 2000; ++k) {
            const D3 o{3 * u(rng), 3 * u(rng), 3 + u(rng)};
            D3 d{u(rng) * 0.4 - o[0] / 3, u(rng) * 0.4 - o[1] / 3, -1};
            const double l = len(d);
            for (double& c : d) c /= l;
            // analytic: |o + t d| = 1
            const double b = o[0] * d[0] + o[1] * d[1] + o[2] * d[2], c = len(o) * len(o) - 1,
                         disc = b * b - c;
            prt::bench::MeshHit h;
            const bool got = mesh.intersect(o, d, 1e30, h);
            if (disc > 0.02) {  // clearly hitting: the mesh must too, near the analytic t
                ASSERT_TRUE(got) << k;
                ++hits;
                EXPECT_NEAR(h.t, -b - std::sqrt(disc), 2 * sag / std::sqrt(disc) + 1e-9) << k;
                EXPECT_TRUE(h.front) << "rays from outside meet the outward side";
                EXPECT_GT(h.normal[0] * h.point[0] + h.normal[1] * h.point[1] + h.normal[2] * h.point[2],
                          0.99);
            } else if (disc < -0.02) {
                EXPECT_FALSE(got) << k;
            }
        }
        EXPECT_GT(hits, 300);
        for (int k = 0; k < 500; ++k) {
            const D3 p{2 * u(rng), 2 * u(rng), 2 * u(rng)};
            const double d = mesh.distance(p), r = len(p);
            EXPECT_LE(d, std::abs(r - 1) + sag + 1e-12) << k;
            EXPECT_GE(d, std::abs(r - 1) - sag - 1e-12) << k;
        }
    }
}

TEST(MeshReference, DistanceToOneTriangleInEveryRegion) {
    const prt::bench::MeshReference m({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}}, {{{0, 1, 2}}});
    EXPECT_NEAR(m.distance({0.5, 0.5, 3}), 3, 1e-12);             // above the face
    EXPECT_NEAR(m.distance({-1, -1, 0}), std::sqrt(2.0), 1e-12);  // beyond vertex 0
    EXPECT_NEAR(m.distance({1, -2, 1}), std::sqrt(5.0), 1e-12);   // beyond edge 01
    EXPECT_NEAR(m.distance({2, 2, 0}), std::sqrt(2.0), 1e-12);    // beyond the hypotenuse
    EXPECT_NEAR(m.distance({3, 0, 0}), 1, 1e-12);                 // beyond vertex 1
    EXPECT_THROW(prt::bench::MeshReference({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {{{0, 1, 2}}}), prt::Error);
}

TEST(PointIndex, NearestAndKnnEqualBruteForce) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<D3> pts(3000);
    for (D3& p : pts) p = {u(rng), u(rng) * 0.1, u(rng)};
    pts.push_back(pts[17]);  // a coincident pair
    const prt::bench::PointIndex index(pts);
    std::vector<double> got;
    for (int k = 0; k < 300; ++k) {
        const D3 q{1.2 * u(rng), 0.2 * u(rng), 1.2 * u(rng)};
        std::vector<double> all;
        for (const D3& p : pts) all.push_back(len({p[0] - q[0], p[1] - q[1], p[2] - q[2]}));
        std::sort(all.begin(), all.end());
        double d;
        index.nearest(q, d);
        EXPECT_DOUBLE_EQ(d, all[0]);
        index.knn(q, 8, ~0u, got);
        ASSERT_EQ(got.size(), 8u);
        for (int i = 0; i < 8; ++i) EXPECT_NEAR(got[i], all[i], 1e-15);
    }
    index.knn(pts[17], 1, 17, got);  // the twin, not itself
    EXPECT_EQ(got.at(0), 0.0);
}

TEST(PointIndex, LocalSpacingIsTheSquareRootOfTheAreaPerPoint) {
    // Uniform random points on a 1 x 1 square at density rho: spacing 1 / sqrt(rho).
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<D3> pts(40000);
    for (D3& p : pts) p = {u(rng), 0.0, u(rng)};
    const prt::bench::PointIndex index(pts);
    std::vector<double> s = index.local_spacing(2);
    std::vector<double> interior;
    for (std::size_t i = 0; i < pts.size(); ++i)
        if (pts[i][0] > 0.05 && pts[i][0] < 0.95 && pts[i][2] > 0.05 && pts[i][2] < 0.95)
            interior.push_back(s[i]);
    std::sort(interior.begin(), interior.end());
    const double median = interior[interior.size() / 2], expected = 1 / std::sqrt(40000.0);
    EXPECT_NEAR(median / expected, 1.0, 0.12);
}

// ---- prt-fidelity end to end ---------------------------------------------------------------------

namespace {

bool have_tools() {
    for (const char* t : {"prt-fidelity", "prt-synth", "prt-radii", "prt-octree", "prt-mls"})
        if (!fs::exists(fs::path(PRT_BIN_DIR) / t)) return false;
    return true;
}

/// Writes the UV sphere as an ASCII OFF file.
void write_off(const fs::path& path, double r) {
    std::vector<D3> v;
    std::vector<std::array<std::uint32_t, 3>> t;
    uv_sphere(r, 96, 192, false, v, t);
    std::ofstream f(path);
    f << "OFF\n" << v.size() << " " << t.size() << " 0\n";
    f.precision(17);
    for (const D3& p : v) f << p[0] << " " << p[1] << " " << p[2] << "\n";
    for (const auto& x : t) f << "3 " << x[0] << " " << x[1] << " " << x[2] << "\n";
}

/// The sphere pool's points minus those with y > cap_y, plus `floaters` points at radius 1.4 below
/// the equator.
void edit_pool(const fs::path& in, const fs::path& out, double cap_y, int floaters) {
    const prt::pool::PoolFile p = prt::pool::PoolFile::open(in);
    prt::pre::PointCloud c = prt::pre::read_point_sections(p), kept;
    for (std::size_t i = 0; i < c.size(); ++i)
        if (c.positions[i][1] <= cap_y) {
            kept.positions.push_back(c.positions[i]);
            kept.normals.push_back(c.normals[i]);
        }
    std::mt19937 rng(1);
    std::normal_distribution<double> g;
    for (int k = 0; k < floaters; ++k) {
        D3 q{g(rng), g(rng), g(rng)};
        q[1] = -std::abs(q[1]) - 0.5;  // below the equator: away from the cap, so they hide no hole
        const double l = len(q);
        for (double& x : q) x *= 1.4 / l;
        kept.positions.push_back(q);
        kept.normals.push_back({float(q[0] / 1.4), float(q[1] / 1.4), float(q[2] / 1.4)});
    }
    prt::pool::PoolWriter w;
    prt::pre::write_point_sections(kept, w);
    w.write(out);
}

nlohmann::json run_fidelity(const fs::path& dir, const std::string& args) {
    const auto r =
        prt::test::run_tool("prt-fidelity", args + " --json " + (dir / "f.json").string() + " -q", dir);
    EXPECT_EQ(r.code, 0) << r.err;
    std::ifstream f(dir / "f.json");
    return nlohmann::json::parse(f);
}

}  // namespace

TEST(PrtFidelity, SphereWithAPlantedHoleAndFloatingPoints) {
    if (!have_tools()) GTEST_SKIP() << "prt-fidelity or the pipeline tools are not built (FLANN, OpenMesh)";
#ifndef PRT_TEST_HAVE_OPENMESH
    GTEST_SKIP() << "this build has no OpenMesh: prt-fidelity reads no mesh reference (the sphere's OFF file)";
#endif
    const fs::path dir = temp_dir("sphere");
    const std::string bin = PRT_BIN_DIR;
    const fs::path full = dir / "full.pool", holed = dir / "holed.pool", off = dir / "sphere.off";
    write_off(off, 1.0);
    ASSERT_EQ(prt::test::run_tool("prt-synth", "sphere -n 30000 -o " + full.string() + " -q", dir).code, 0);
    // The cap y > 0.8 removed: 10 % of the sphere's area (a zone's area is proportional to its height).
    edit_pool(full, holed, 0.8, 200);
    for (const fs::path& p : {full, holed}) {
        for (const char* step : {"prt-radii", "prt-octree", "prt-mls"})
            ASSERT_EQ(prt::test::run_tool(step, p.string() + " -o " + p.string() + " -q", dir).code, 0)
                << step;
    }
    const std::string common = " --reference " + off.string() + " --width 96 --height 96 --views 6";

    // The full sphere: every view sees data everywhere; no hole, no false hit, small errors.
    const nlohmann::json a = run_fidelity(dir, full.string() + common);
    EXPECT_EQ(a["reference_pixels"]["uncovered"], 0);
    for (const char* s : {"splats", "mls"}) {
        const auto& r = a["surfaces"][s];
        EXPECT_LE(r["hole_rate"].get<double>(), 0.002) << s;
        EXPECT_LE(r["false_hit_rate"].get<double>(), 0.002) << s;
        EXPECT_LT(r["depth_error_spacings"]["median"].get<double>(), 0.25) << s;
        EXPECT_LT(r["normal_error_degrees"]["median"].get<double>(), 2.0) << s;
    }

    // The cap removed, judged with the full sphere's points as the data: the cap is a hole. Its
    // share of covered pixels is the mean over views of its projected area over the sphere's.
    const nlohmann::json b = run_fidelity(dir, holed.string() + common + " --points " + full.string());
    double expected = 0;
    for (const auto& v : b["per_view"]) {
        const double dy = v["direction"][1].get<double>();
        // projected area of the cap y > 0.8 seen along d, over pi: numeric, by sampling the disk
        int in = 0, total = 0;
        for (int i = -200; i <= 200; ++i)
            for (int j = -200; j <= 200; ++j) {
                const double x = i / 200.0, z = j / 200.0;
                if (x * x + z * z > 1) continue;
                ++total;
                // the visible point of the unit sphere behind image point (x, z) in a frame whose
                // third axis is the view direction: its height along y is x*ey + sqrt(1-r2)*dy, with
                // ey the component of y across the view; |ey| = sqrt(1 - dy^2)
                const double h = x * std::sqrt(1 - dy * dy) + std::sqrt(1 - x * x - z * z) * dy;
                in += h > 0.8;
            }
        expected += double(in) / total / b["per_view"].size();
    }
    for (const char* s : {"splats", "mls"}) {
        const double holes = b["surfaces"][s]["hole_rate"].get<double>();
        EXPECT_NEAR(holes, expected, 0.35 * expected + 0.004) << s;
        // the 200 floating points become floating discs: false hits, a few per view
        EXPECT_GT(b["surfaces"][s]["false_hits"].get<int>(), 0) << s;
    }
    // The holed pool's own points: the cap has no data, so it is no hole; only the band of
    // --coverage spacings around the data's edge, where the surface stops sooner, counts.
    const nlohmann::json c = run_fidelity(dir, holed.string() + common);
    EXPECT_GT(c["reference_pixels"]["uncovered"].get<int>(), 0);
    EXPECT_LE(c["surfaces"]["mls"]["hole_rate"].get<double>(), 0.25 * expected);
    fs::remove_all(dir);
}

TEST(PrtFidelity, AnalyticTruthOfAScanAndTheScannersViews) {
    if (!have_tools()) GTEST_SKIP() << "prt-fidelity or the pipeline tools are not built (FLANN, OpenMesh)";
    const fs::path dir = temp_dir("scan");
    const fs::path scan = dir / "scan.pool";
    // a sphere seen by two scanners, true normals (the reference is the analytic sphere)
    ASSERT_EQ(
        prt::test::run_tool(
            "prt-synth",
            "sphere --scan --scanners 2 --sample-step 0.1 --scan-normals -o " + scan.string() + " -q", dir)
            .code,
        0);
    for (const char* step : {"prt-radii", "prt-octree", "prt-mls"})
        ASSERT_EQ(prt::test::run_tool(step, scan.string() + " -o " + scan.string() + " -q", dir).code, 0)
            << step;
    const nlohmann::json a = run_fidelity(dir, scan.string() + " --width 96 --height 96 --views 6");
    EXPECT_EQ(a["reference"]["kind"], "analytic");
    // two scanners see part of the sphere: some reference pixels have no data
    EXPECT_GT(a["reference_pixels"]["uncovered"].get<int>(), 0);
    EXPECT_GT(a["reference_pixels"]["covered"].get<int>(), 0);
    for (const char* s : {"splats", "mls"}) {
        EXPECT_LE(a["surfaces"][s]["hole_rate"].get<double>(), 0.005) << s;
        EXPECT_LE(a["surfaces"][s]["false_hit_rate"].get<double>(), 0.005) << s;
    }
    // from the scanners: 6 cube faces each
    const nlohmann::json b =
        run_fidelity(dir, scan.string() + " --width 64 --height 64 --views-from sensors");
    EXPECT_EQ(b["views"], 12);
    EXPECT_GT(b["reference_pixels"]["covered"].get<int>(), 0);
    // a pool with no shape and no --reference is one line, exit 1
    const fs::path plain = dir / "plain.pool";
    edit_pool(scan, plain, 10.0, 0);  // the same points without provenance
    for (const char* step : {"prt-radii", "prt-mls"})
        ASSERT_EQ(prt::test::run_tool(step, plain.string() + " -o " + plain.string() + " -q", dir).code, 0)
            << step;
    const auto r = prt::test::run_tool("prt-fidelity", plain.string() + " --width 16 --height 16", dir);
    EXPECT_EQ(r.code, 1);
    EXPECT_NE(r.err.find("no reference"), std::string::npos) << r.err;
    EXPECT_EQ(prt::test::lines(r.err), 1) << r.err;
    fs::remove_all(dir);
}
