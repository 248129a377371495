// A real scan through the whole runtime (label cpu): the CGAL kitten point set (5,210 points with
// unit normals, ../shared/data/points/cgal_kitten/kitten.xyz), splat radii by brute-force k-NN
// (thesis 3.1, k = 9), the test octree, the default camera of a pool without a scene, and the CPU
// backend. Skips when the shared data folder is absent.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "prt/core/render.h"
#include "prt/cpu/cpu_backend.h"
#include "prt/runtime/render_scene.h"
#include "test_scene.h"

namespace prt::test {
namespace {

TEST(RealData, KittenRendersWithoutHolesOrNaN) {
    const std::filesystem::path file =
        std::filesystem::path(PRT_SHARED_DATA_DIR) / "points/cgal_kitten/kitten.xyz";
    if (!std::filesystem::exists(file))
        GTEST_SKIP() << "shared data not found: " << file << " (needs ../shared/data)";
    std::ifstream in(file);
    std::vector<TestPoint> pts;
    double x, y, z, nx, ny, nz;
    while (in >> x >> y >> z >> nx >> ny >> nz) pts.push_back({{x, y, z}, d3_norm({nx, ny, nz}), 0.0});
    ASSERT_EQ(pts.size(), 5210u);
    // thesis 3.1: radius = distance to the 9th nearest neighbour (brute force, double).
    double max_radius = 0;
    for (auto& p : pts) {
        std::vector<double> d;
        d.reserve(pts.size());
        for (const auto& q : pts) d.push_back(d3_len(d3_sub(p.position, q.position)));
        std::nth_element(d.begin(), d.begin() + 9, d.end());  // d[0] is the point itself
        p.radius = d[9];
        max_radius = std::max(max_radius, p.radius);
    }
    const TestModel model = make_model(pts, {0.01, -0.02, 0.03});
    scene::Scene sc;
    sc.materials.push_back(scene::Material{});
    sc.camera.width = sc.camera.height = 64;
    rt::RenderScene rs = rt::RenderScene::from_pools(sc, {make_pool(model)});
    // The default camera of a pool alone: framing the model's bounds.
    rs.scene().camera = rt::RenderScene::framing_camera(rs.world_min(), rs.world_max(), 64, 64);
    scene::PointLight pl;
    pl.position = {1, 2, 2};
    rs.scene().point_lights = {pl};
    rs.update_lights();
    const core::SceneView view = rs.view();
    const core::PinholeCamera cam = rs.camera();
    int hits = 0, far_hits = 0;
    for (std::uint32_t py = 0; py < 64; ++py) {
        for (std::uint32_t px = 0; px < 64; ++px) {
            core::SurfaceHit h;
            core::RayCounters c;
            if (!core::closest_hit_scene(view, core::primary_ray(cam, px, py, 64, 64), h, c)) continue;
            ++hits;
            // Every hit lies on some input point's splat: within its radius of that point.
            const auto& o = rs.render_origin();
            const D3 p{o[0] + h.position.x, o[1] + h.position.y, o[2] + h.position.z};
            bool near = false;
            for (const auto& q : pts)
                near = near || d3_len(d3_sub(p, q.position)) <= q.radius * 1.0001 + 1e-6;
            far_hits += !near;
        }
    }
    EXPECT_GT(hits, 64 * 64 / 5) << "the framed kitten should fill a good part of the image";
    EXPECT_EQ(far_hits, 0) << "hits away from every splat";
    auto backend = cpu::make_cpu_backend(0);
    backend->set_scene(view);
    rt::FrameRequest req;
    req.camera = cam;
    req.params = rs.params();
    req.width = req.height = 64;
    rt::Image img;
    const rt::FrameStats s = backend->render(req, img);
    EXPECT_EQ(s.sanitized, 0u);
    EXPECT_EQ(s.truncated, 0u);
    for (float v : img.rgb) ASSERT_TRUE(std::isfinite(v));
}

}  // namespace
}  // namespace prt::test
