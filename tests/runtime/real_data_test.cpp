// A real scan through the whole runtime (label cpu): the CGAL kitten point set (5,210 points with
// unit normals, ../shared/data/points/cgal_kitten/kitten.xyz), splat radii by brute-force k-NN
// (thesis 3.1, k = 9), the test octree, the default camera of a pool without a scene, and the CPU
// backend. Skips when the shared data folder is absent.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "prt/core/render.h"
#include "prt/cpu/cpu_backend.h"
#include "prt/runtime/render_scene.h"
#include "prt/runtime/scan_frame.h"
#include "test_scene.h"
#include "tool_run.h"

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

// prt-play --up auto on a real scene scan: the PCL mug scene (a stereo rig's organized cloud of a
// table top with a mug, and the floor beyond the table's edge). Its table top is the dominant
// plane; the sign is checked against facts read from the data, not assumed: the rig's camera is
// at the origin (every point has z > 0.69: the camera looks along +z) and the cloud's rows run top
// to bottom with y growing (the first rows' y is below the last rows'), so the image's up is -y;
// a table top's normal, seen from above, points toward the camera and up the image.
TEST(RealData, MugSceneTableTopGivesTheUp) {
    namespace fs = std::filesystem;
    const fs::path file = fs::path(PRT_SHARED_DATA_DIR) / "points/pcl/table_scene_mug_stereo_textured.pcd";
    if (!fs::exists(file)) GTEST_SKIP() << "shared data not found: " << file << " (needs ../shared/data)";
    if (!fs::exists(fs::path(PRT_BIN_DIR) / "prt-import")) GTEST_SKIP() << "prt-import was not built";
#ifndef PRT_TEST_HAVE_PCL
    GTEST_SKIP() << "this build has no PCL: prt-import reads no PCD";
#endif
    const fs::path dir = fs::temp_directory_path() / ("prt_mug_up_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const ToolRun r =
        run_tool("prt-import", file.string() + " -o " + (dir / "mug.pool").string() + " -q", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    const pool::PoolFile pf = pool::PoolFile::open(dir / "mug.pool");
    const auto pos = pf.array<pool::Float3>(pool::SectionType::positions);
    const pool::ModelInfo& info = pf.model_info();
    ASSERT_GT(pos.size(), 200000u);
    auto world = [&](std::size_t i) {
        return D3{pos[i].x + info.origin[0], pos[i].y + info.origin[1], pos[i].z + info.origin[2]};
    };
    // The facts from the data: the camera at the origin looks along +z; image rows run down +y.
    double min_z = 1e300, first_y = 0, last_y = 0;
    const std::size_t rows = 2000;
    for (std::size_t i = 0; i < pos.size(); ++i) min_z = std::min(min_z, world(i)[2]);
    for (std::size_t i = 0; i < rows; ++i) {
        first_y += world(i)[1] / rows;
        last_y += world(pos.size() - 1 - i)[1] / rows;
    }
    ASSERT_GT(min_z, 0.5) << "the rig's camera should sit at the origin, looking along +z";
    ASSERT_LT(first_y, last_y) << "the first rows should be the top of the image (y grows down)";

    rt::UpInput in;
    in.positions = pos;
    in.normals = pf.array<pool::Float3>(pool::SectionType::normals);
    in.sensors = pf.array<pool::Sensor>(pool::SectionType::sensors);
    in.origin = {info.origin[0], info.origin[1], info.origin[2]};
    const rt::UpDetection d = rt::detect_up(in);
    EXPECT_EQ(d.rule, rt::UpRule::plane) << d.description;
    EXPECT_GT(d.plane_fraction, 0.4) << d.description;
    const D3 up{d.up[0], d.up[1], d.up[2]};
    const D3 table = d3_add(D3{d.plane_point[0], d.plane_point[1], d.plane_point[2]}, in.origin);
    EXPECT_GT(d3_dot(up, d3_mul(table, -1.0)), 0.2)
        << "the table's up should face the camera at the origin: " << rt::direction_name(d.up);
    EXPECT_GT(-up[1], 0.7) << "the table's up should point up the image (-y): " << rt::direction_name(d.up);
    // The mug stands on the table: points 2 to 15 cm above its plane over the table, none as many below.
    std::size_t above = 0, below = 0;
    for (std::size_t i = 0; i < pos.size(); i += 7) {
        const D3 q = d3_sub(world(i), table);
        const double h = d3_dot(q, up);
        if (d3_len(d3_sub(q, d3_mul(up, h))) > 0.3) continue;  // near the table's middle
        above += h > 0.02 && h < 0.15;
        below += h < -0.02 && h > -0.15;
    }
    EXPECT_GT(above, 200u);
    EXPECT_LT(below, above / 10) << above << " above, " << below << " below";
    fs::remove_all(dir);
}

}  // namespace
}  // namespace prt::test
