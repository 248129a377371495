// Scanner intensities shading the image (SCENE.md materials[].point_colors, prt-iso --point-colors):
// a plane whose intensity grows along x, written here with PoolWriter and pre::write_point_sections,
// its splat, MLS and ISO sections made by the real tools, rendered by the CPU backend. Each pixel's
// radiance with "intensity" over its radiance with "none" (same light, same geometry; no ambient or
// specular term) is the grey level's linear value, which must equal t = (I(x) - lo) / (hi - lo)
// clamped, with I(x) known analytically at the pixel's analytic hit on the plane and [lo, hi] the
// 1st-99th percentile computed here by sorting (or the scene's intensity_range).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "point_cloud.h"
#include "prt/core/render.h"
#include "prt/cpu/cpu_backend.h"
#include "prt/runtime/render_scene.h"
#include "surface_fixtures.h"

namespace prt::test {
namespace {

namespace fs = std::filesystem;

constexpr int k_side = 120;  // points per side of the plane [0, 2]^2 at z = 0
double intensity_at(double x) {
    return 1000.0 + 500.0 * x;  // raw scanner values, 1000 .. 2000
}

class PointColorsTest : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        s_dir = new TempDir("prt-point-colors-test");
        for (const char* t : {"prt-octree", "prt-iso", "prt-mls"})
            if (!fs::exists(fs::path(PRT_BIN_DIR) / t)) return;
        // The plane, normals +z, intensity along x; a second pool with colors as well.
        pre::PointCloud cloud;
        for (int i = 0; i < k_side; ++i) {
            for (int j = 0; j < k_side; ++j) {
                const double x = 2.0 * (i + 0.5) / k_side, y = 2.0 * (j + 0.5) / k_side;
                cloud.positions.push_back({x, y, 0.0});
                cloud.normals.push_back({0, 0, 1});
                cloud.intensities.push_back(static_cast<float>(intensity_at(x)));
            }
        }
        // thesis 3.1's k-NN radius for uniform density (k = 9): sqrt(9 A / (pi n)).
        cloud.radii.assign(cloud.size(),
                           static_cast<float>(std::sqrt(9.0 * 4.0 / (3.14159265358979 * cloud.size()))));
        for (int with_colors = 0; with_colors < 2; ++with_colors) {
            if (with_colors) cloud.colors.assign(cloud.size(), pool::Rgba8{255, 40, 40, 255});
            const fs::path p = s_dir->path / (with_colors ? "rgb_plane.pool" : "plane.pool");
            pool::PoolWriter w;
            pre::write_point_sections(cloud, w);
            w.write(p);
            const std::string q = " -q";
            for (const std::string& step : {std::string("prt-octree"), std::string("prt-mls"),
                                            std::string("prt-iso --point-colors intensity")}) {
                const std::string tool = step.substr(0, step.find(' '));
                const std::string extra = step.size() > tool.size() ? step.substr(tool.size()) : "";
                const ToolRun r = run_tool(tool, p.string() + " -o " + p.string() + extra + q, s_dir->path);
                if (r.code != 0) {
                    s_error = tool + ": " + r.err;
                    return;
                }
            }
        }
        // The reference range: nearest-rank 1st and 99th percentiles of the intensities.
        std::vector<float> v = cloud.intensities;
        std::sort(v.begin(), v.end());
        s_lo = v[static_cast<std::size_t>(std::llround(0.01 * (v.size() - 1)))];
        s_hi = v[static_cast<std::size_t>(std::llround(0.99 * (v.size() - 1)))];
        s_ready = true;
    }
    static void TearDownTestSuite() {
        delete s_dir;
        s_dir = nullptr;
    }
    void SetUp() override {
        if (!s_error.empty()) FAIL() << s_error;
        if (!s_ready) GTEST_SKIP() << "prt-octree, prt-iso or prt-mls was not built";
    }

    /// A scene looking straight down at the plane, one light far above, no ambient or specular.
    static scene::Scene plane_scene(const std::string& pool, scene::SurfaceKind surface,
                                    scene::PointColors pc,
                                    std::optional<std::array<float, 2>> range = std::nullopt) {
        scene::Scene sc;
        sc.camera.position = {1, 1, 3};
        sc.camera.look_at = {1, 1, 0};
        sc.camera.up = {0, 1, 0};
        sc.camera.fov_y_degrees = 40;
        sc.camera.width = sc.camera.height = 48;
        scene::Material m;
        m.ambient = {0, 0, 0};
        m.specular = {0, 0, 0};
        m.diffuse = {0.8f, 0.8f, 0.8f};
        m.point_colors = pc;
        m.intensity_range = range;
        sc.materials = {m};
        scene::PointLight light;
        light.position = {1, 1, 50};
        sc.point_lights = {light};
        sc.render.shadows = false;
        sc.render.reflections = false;
        sc.models.push_back(scene::Model{});
        sc.models.back().name = "plane";
        sc.models.back().pool = s_dir->path / pool;
        sc.models.back().surface = surface;
        return sc;
    }

    /// Radiance (green channel, linear) per pixel through the CPU backend, and the hit's x on the
    /// plane z = 0 from the pixel's ray (analytic); x is NaN where the ray misses the square.
    struct Frame {
        std::vector<double> value, x;
        std::vector<std::string> warnings, notes;
    };
    static Frame render(const scene::Scene& sc) {
        const rt::RenderScene rs = rt::RenderScene::load(sc);
        Frame f;
        f.warnings = rs.warnings();
        f.notes = rs.notes();
        auto backend = cpu::make_cpu_backend(0);
        backend->set_scene(rs.view());
        rt::FrameRequest req;
        req.camera = rs.camera();
        req.params = rs.params();
        req.width = sc.camera.width;
        req.height = sc.camera.height;
        rt::Image img;
        backend->render(req, img);
        const auto& o = rs.render_origin();
        for (std::uint32_t py = 0; py < req.height; ++py) {
            for (std::uint32_t px = 0; px < req.width; ++px) {
                const core::Ray r = core::primary_ray(req.camera, px, py, req.width, req.height);
                const double t = -(r.origin.z + o[2]) / r.dir.z;
                const double x = r.origin.x + o[0] + t * r.dir.x, y = r.origin.y + o[1] + t * r.dir.y;
                const bool inside = x > 0.15 && x < 1.85 && y > 0.15 && y < 1.85;  // away from the edges
                f.x.push_back(inside ? x : std::nan(""));
                f.value.push_back(img.rgb[(py * req.width + px) * 3 + 1]);
            }
        }
        return f;
    }

    /// The largest |shaded / plain - t(x)| over the judged pixels, and their count.
    static double worst(const Frame& shaded, const Frame& plain, double lo, double hi, int* judged) {
        double w = 0;
        *judged = 0;
        for (std::size_t i = 0; i < shaded.x.size(); ++i) {
            if (std::isnan(shaded.x[i])) continue;
            EXPECT_GT(plain.value[i], 0.05) << "the plain render should be lit at pixel " << i;
            const double t = std::clamp((intensity_at(shaded.x[i]) - lo) / (hi - lo), 0.0, 1.0);
            w = std::max(w, std::fabs(shaded.value[i] / plain.value[i] - t));
            ++*judged;
        }
        return w;
    }

    static TempDir* s_dir;
    static bool s_ready;
    static std::string s_error;
    static double s_lo, s_hi;
};
TempDir* PointColorsTest::s_dir = nullptr;
bool PointColorsTest::s_ready = false;
std::string PointColorsTest::s_error;
double PointColorsTest::s_lo = 0, PointColorsTest::s_hi = 0;

TEST_F(PointColorsTest, SplatsAndMlsShadeByIntensity) {
    for (const scene::SurfaceKind surface : {scene::SurfaceKind::splats, scene::SurfaceKind::mls}) {
        const Frame plain = render(plane_scene("plane.pool", surface, scene::PointColors::none));
        const Frame shaded = render(plane_scene("plane.pool", surface, scene::PointColors::intensity));
        int judged = 0;
        EXPECT_LT(worst(shaded, plain, s_lo, s_hi, &judged), 0.03) << "surface " << static_cast<int>(surface);
        EXPECT_GT(judged, 1000);
        // Brighter where the intensity is higher: the right quarter against the left quarter.
        double left = 0, right = 0;
        for (std::size_t i = 0; i < shaded.x.size(); ++i) {
            if (shaded.x[i] < 0.5) left += shaded.value[i];
            if (shaded.x[i] > 1.5) right += shaded.value[i];
        }
        EXPECT_GT(right, 4 * left);
        ASSERT_EQ(shaded.notes.size(), 1u);
        EXPECT_NE(shaded.notes[0].find("1st-99th percentile"), std::string::npos) << shaded.notes[0];
        // auto on a pool with intensities and no colors is intensity.
        const Frame automatic = render(plane_scene("plane.pool", surface, scene::PointColors::automatic));
        EXPECT_EQ(automatic.value, shaded.value);
    }
}

TEST_F(PointColorsTest, IntensityRangeOfTheScene) {
    const std::array<float, 2> range{1250.0f, 1750.0f};  // x = 0.5 .. 1.5 to black..white
    const Frame plain =
        render(plane_scene("plane.pool", scene::SurfaceKind::splats, scene::PointColors::none));
    const Frame shaded =
        render(plane_scene("plane.pool", scene::SurfaceKind::splats, scene::PointColors::intensity, range));
    int judged = 0;
    EXPECT_LT(worst(shaded, plain, 1250.0, 1750.0, &judged), 0.04);
    EXPECT_GT(judged, 1000);
}

TEST_F(PointColorsTest, IsoBakesIntensityWithPrtIso) {
    // prt-iso --point-colors intensity baked the grey levels into the leaves: the scene's point
    // colors (auto) take them; "none" gives the plain render.
    const Frame plain = render(plane_scene("plane.pool", scene::SurfaceKind::iso, scene::PointColors::none));
    const Frame baked =
        render(plane_scene("plane.pool", scene::SurfaceKind::iso, scene::PointColors::automatic));
    int judged = 0;
    EXPECT_LT(worst(baked, plain, s_lo, s_hi, &judged), 0.06);
    EXPECT_GT(judged, 1000);
    // Asking the renderer for intensity on an ISO model says where the colors come from.
    const Frame asked =
        render(plane_scene("plane.pool", scene::SurfaceKind::iso, scene::PointColors::intensity));
    ASSERT_EQ(asked.warnings.size(), 1u);
    EXPECT_NE(asked.warnings[0].find("prt-iso --point-colors intensity"), std::string::npos)
        << asked.warnings[0];
}

TEST_F(PointColorsTest, ColorsWinOverIntensityUnlessAsked) {
    // The pool with red colors and intensities: auto and colors take the colors, intensity the grey.
    const Frame plain =
        render(plane_scene("rgb_plane.pool", scene::SurfaceKind::splats, scene::PointColors::none));
    for (const scene::PointColors pc : {scene::PointColors::automatic, scene::PointColors::colors}) {
        const Frame colors = render(plane_scene("rgb_plane.pool", scene::SurfaceKind::splats, pc));
        // Green 40 / 255 in sRGB is 0.0212 linear, on every judged pixel.
        for (std::size_t i = 0; i < colors.x.size(); ++i) {
            if (!std::isnan(colors.x[i])) {
                EXPECT_NEAR(colors.value[i] / plain.value[i], 0.0212, 0.002);
            }
        }
    }
    const Frame grey =
        render(plane_scene("rgb_plane.pool", scene::SurfaceKind::splats, scene::PointColors::intensity));
    int judged = 0;
    EXPECT_LT(worst(grey, plain, s_lo, s_hi, &judged), 0.03);
}

TEST_F(PointColorsTest, IntensityWithoutIntensitiesWarnsAndShadesWhite) {
    pool::PoolWriter w;
    const auto full = pool::PoolFile::open(s_dir->path / "plane.pool");
    w.carry_over(full);
    w.remove(pool::SectionType::intensities);
    w.write(s_dir->path / "bare.pool");
    const Frame plain =
        render(plane_scene("bare.pool", scene::SurfaceKind::splats, scene::PointColors::none));
    const Frame asked =
        render(plane_scene("bare.pool", scene::SurfaceKind::splats, scene::PointColors::intensity));
    ASSERT_EQ(asked.warnings.size(), 1u);
    EXPECT_NE(asked.warnings[0].find("no intensities"), std::string::npos) << asked.warnings[0];
    EXPECT_EQ(asked.value, plain.value);
}

}  // namespace
}  // namespace prt::test
