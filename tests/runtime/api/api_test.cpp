// The public C++ API (prt/pointrt.h, issue 18) through its header only: rays at a unit sphere (made
// by prt-synth, prt-radii, prt-octree) against the exact ray-sphere intersection; invalid rays
// reported per ray; empty batches; errors (device memory on the CPU backend, a missing surface, a
// missing file) as one line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <system_error>
#include <vector>

#include "prt/pointrt.h"
#include "tool_run.h"

namespace {

namespace fs = std::filesystem;

/// A temporary folder removed at exit.
struct TempFolder {
    fs::path path = fs::temp_directory_path() / ("prt_api_test_" + std::to_string(::getpid()));
    TempFolder() { fs::create_directories(path); }
    ~TempFolder() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
};

/// A 20k-point unit sphere pool, made once.
const fs::path& sphere_pool() {
    static const TempFolder folder;
    static const fs::path pool = [] {
        const fs::path& dir = folder.path;
        const fs::path p = dir / "s.pool";
        EXPECT_EQ(prt::test::run_tool("prt-synth", "sphere -n 20000 -o " + p.string() + " -q", dir).code, 0);
        for (const char* t : {"prt-radii", "prt-octree"})
            EXPECT_EQ(prt::test::run_tool(t, p.string() + " -o " + p.string() + " -q", dir).code, 0);
        return p;
    }();
    return pool;
}

pointrt::Options cpu() {
    pointrt::Options o;
    o.backend = "cpu";
    return o;
}

/// First root of |o + t d| = 1, or NaN.
double sphere_t(const double o[3], const double d[3]) {
    const double a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    const double b = 2 * (o[0] * d[0] + o[1] * d[1] + o[2] * d[2]);
    const double c = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - 1;
    const double disc = b * b - 4 * a * c;
    return disc < 0 ? NAN : (-b - std::sqrt(disc)) / (2 * a);
}

TEST(PointrtApi, HitsMatchTheAnalyticSphere) {
    pointrt::Scene s = pointrt::Scene::open(sphere_pool().string(), cpu());
    EXPECT_EQ(s.info().backend, "cpu");
    ASSERT_EQ(s.info().surfaces.size(), 1u);
    EXPECT_EQ(s.info().surfaces[0], "splats");
    std::mt19937 rng(5);
    std::normal_distribution<double> g;
    const std::size_t n = 1000;
    std::vector<double> o(n * 3), d(n * 3);
    for (std::size_t i = 0; i < n; ++i) {
        double a[3] = {g(rng), g(rng), g(rng)}, b[3] = {g(rng), g(rng), g(rng)};
        const double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        const double lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        for (int k = 0; k < 3; ++k) {
            o[i * 3 + k] = 3 * a[k] / la;
            d[i * 3 + k] = 0.5 * b[k] / lb - o[i * 3 + k];  // toward a point inside radius 0.5
        }
    }
    pointrt::RayArrays rays;
    rays.count = n;
    rays.origins = o.data();
    rays.directions = d.data();
    rays.origins_f64 = rays.directions_f64 = true;
    std::vector<std::uint8_t> hit(n), valid(n);
    std::vector<float> t(n), normal(n * 3);
    std::vector<std::int64_t> element(n);
    pointrt::HitArrays out;
    out.hit = hit.data();
    out.valid = valid.data();
    out.t = t.data();
    out.normal = normal.data();
    out.element = element.data();
    const pointrt::CastStats st = s.cast(rays, out);
    EXPECT_EQ(st.rays, n);
    double worst = 0, worst_cos = 1;
    for (std::size_t i = 0; i < n; ++i) {
        ASSERT_TRUE(hit[i] && valid[i]) << i;
        const double ref = sphere_t(&o[i * 3], &d[i * 3]);
        const double len =
            std::sqrt(d[i * 3] * d[i * 3] + d[i * 3 + 1] * d[i * 3 + 1] + d[i * 3 + 2] * d[i * 3 + 2]);
        worst = std::max(worst, std::abs(t[i] - ref) * len);
        double cos = 0;
        for (int k = 0; k < 3; ++k) cos += normal[i * 3 + k] * (o[i * 3 + k] + ref * d[i * 3 + k]);
        worst_cos = std::min(worst_cos, cos);
        EXPECT_GE(element[i], 0);
        EXPECT_LT(element[i], 20000);
    }
    EXPECT_LT(worst, 3e-3);
    EXPECT_GT(worst_cos, 0.999);

    // The vector interface gives the same answers.
    std::vector<pointrt::Ray> v(10);
    for (std::size_t i = 0; i < v.size(); ++i)
        for (int k = 0; k < 3; ++k) {
            v[i].origin[k] = o[i * 3 + k];
            v[i].direction[k] = d[i * 3 + k];
        }
    const std::vector<pointrt::Hit> hv = s.cast(v);
    for (std::size_t i = 0; i < v.size(); ++i) {
        EXPECT_TRUE(hv[i].hit);
        EXPECT_FLOAT_EQ(hv[i].t, t[i]);
        EXPECT_EQ(hv[i].element, element[i]);
        EXPECT_EQ(hv[i].model, 0);
    }
}

TEST(PointrtApi, InvalidRaysAreReportedPerRay) {
    pointrt::Scene s = pointrt::Scene::open(sphere_pool().string(), cpu());
    std::vector<pointrt::Ray> v(6);
    for (auto& r : v) r.origin = {0, 0, 3}, r.direction = {0, 0, -1};
    v[1].origin[0] = NAN;
    v[2].direction = {0, 0, 0};
    v[3].t_min = -1;
    v[4].direction[2] = -INFINITY;
    v[5].t_max = NAN;
    const std::vector<pointrt::Hit> h = s.cast(v);
    EXPECT_TRUE(h[0].hit && h[0].valid);
    for (int i = 1; i < 6; ++i) {
        EXPECT_FALSE(h[i].valid) << i;
        EXPECT_FALSE(h[i].hit) << i;
        EXPECT_EQ(h[i].model, -1);
        EXPECT_TRUE(std::isinf(h[i].t));
    }
    const std::vector<std::uint8_t> occ = s.occluded(v);
    EXPECT_EQ(occ, (std::vector<std::uint8_t>{1, 0, 0, 0, 0, 0}));
}

TEST(PointrtApi, EmptyBatchesAndOcclusionSegments) {
    pointrt::Scene s = pointrt::Scene::open(sphere_pool().string(), cpu());
    EXPECT_TRUE(s.cast(std::vector<pointrt::Ray>{}).empty());
    pointrt::RayArrays none;
    EXPECT_EQ(s.cast(none, pointrt::HitArrays{}).rays, 0u);
    EXPECT_EQ(s.occluded(none, nullptr).rays, 0u);
    // A segment ending before the sphere is clear, one reaching it is blocked.
    std::vector<pointrt::Ray> v(2);
    for (auto& r : v) r.origin = {0, 0, 3}, r.direction = {0, 0, -1};
    v[0].t_max = 1.9f;
    v[1].t_max = 2.1f;
    EXPECT_EQ(s.occluded(v), (std::vector<std::uint8_t>{0, 1}));
}

TEST(PointrtApi, ErrorsAreOneLine) {
    const auto one_line = [](const pointrt::Error& e, const char* word) {
        const std::string m = e.what();
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
        EXPECT_NE(m.find(word), std::string::npos) << m;
    };
    try {
        pointrt::Scene::open("/nonexistent/x.pool", cpu());
        ADD_FAILURE() << "opened a missing file";
    } catch (const pointrt::Error& e) {
        one_line(e, "x.pool");
    }
    pointrt::Options mls = cpu();
    mls.surface = "mls";
    try {
        pointrt::Scene::open(sphere_pool().string(), mls);
        ADD_FAILURE() << "traced MLS on a pool without its sections";
    } catch (const pointrt::Error& e) {
        one_line(e, "s.pool");
    }
    pointrt::Scene s = pointrt::Scene::open(sphere_pool().string(), cpu());
    const double o[3] = {0, 0, 3}, d[3] = {0, 0, -1};
    pointrt::RayArrays rays;
    rays.count = 1;
    rays.origins = o;
    rays.directions = d;
    rays.origins_f64 = rays.directions_f64 = true;
    rays.memory = pointrt::Memory::device;
    std::uint8_t flag = 0;
    pointrt::HitArrays out;
    out.hit = &flag;
    out.memory = pointrt::Memory::device;
    try {
        s.cast(rays, out);
        ADD_FAILURE() << "the CPU backend took device memory";
    } catch (const pointrt::Error& e) {
        one_line(e, "cpu backend");
    }
    out.memory = pointrt::Memory::host;
    EXPECT_THROW(s.cast(rays, out), pointrt::Error);  // rays and outputs in different memories
}

TEST(PointrtApi, RenderAndMove) {
    pointrt::Scene s = pointrt::Scene::open(sphere_pool().string(), cpu());
    pointrt::Scene moved = std::move(s);
    pointrt::Camera cam;
    cam.eye = {0, 0, 4};
    const pointrt::Image img = moved.render(cam, 48, 32);
    ASSERT_EQ(img.rgba.size(), 48u * 32u * 4u);
    // The sphere at the centre differs from the background in the corner.
    const std::size_t c = (16 * 48 + 24) * 4;
    EXPECT_NE(std::vector<std::uint8_t>(img.rgba.begin() + c, img.rgba.begin() + c + 3),
              std::vector<std::uint8_t>(img.rgba.begin(), img.rgba.begin() + 3));
    EXPECT_THROW(moved.render(cam, 0, 10), pointrt::Error);
}

}  // namespace
