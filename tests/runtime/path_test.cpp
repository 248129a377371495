// Path tracing (seed 002, 7; prt/core/path.h) against cases with exact answers: a diffuse plane
// under a uniform sky reflects albedo x sky in every sample (no noise); at depth 1 the path tracer
// is the ray tracer's direct light; area lights are seen by camera rays; samples are stratified
// and frames draw new ones; no NaN.
#include <gtest/gtest.h>

#include <cmath>

#include "prt/core/render.h"
#include "prt/runtime/backend.h"
#include "prt/runtime/render_scene.h"
#include "test_scene.h"

namespace prt::test {
namespace {

rt::RenderScene plane_scene(float albedo, scene::Color sky) {
    const auto pts = rect_points({-50, 0, -50}, {100, 0, 0}, {0, 0, 100}, {0, 1, 0}, 200);
    scene::Scene sc;
    scene::Material m;
    m.diffuse = {albedo, albedo, albedo};
    m.ambient = {0, 0, 0};
    m.specular = {0, 0, 0};
    m.point_colors = scene::PointColors::none;
    sc.materials = {m};
    sc.environment.color = sky;
    sc.camera.position = {0, 2, 0.5};
    sc.camera.look_at = {0, 0, 0};
    sc.camera.fov_y_degrees = 40;
    return rt::RenderScene::from_pools(sc, {make_pool(make_model(pts, {0, 0, 0}))});
}

rt::Image render(const rt::RenderScene& rs, const core::RenderParams& p, std::uint32_t w, rt::FrameStats* st = nullptr) {
    auto b = rt::make_backend("cpu");
    b->set_scene(rs.view());
    rt::FrameRequest req;
    req.camera = rs.camera();
    req.params = p;
    req.width = req.height = w;
    rt::Image img;
    const rt::FrameStats s = b->render(req, img);
    if (st) *st = s;
    return img;
}

TEST(PathTracing, ADiffusePlaneUnderAUniformSkyReflectsAlbedoTimesSky) {
    // Every bounce from the plane escapes to the sky: L = albedo x sky exactly, per sample.
    const rt::RenderScene rs = plane_scene(0.6f, {0.5f, 1.0f, 2.0f});
    core::RenderParams p = rs.params();
    p.path_tracing = 1;
    p.spp = 4;
    rt::FrameStats st;
    const rt::Image img = render(rs, p, 32, &st);
    for (std::size_t i = 0; i < img.rgb.size(); i += 3) {
        ASSERT_NEAR(img.rgb[i + 0], 0.3f, 1e-5) << i / 3;
        ASSERT_NEAR(img.rgb[i + 1], 0.6f, 1e-5) << i / 3;
        ASSERT_NEAR(img.rgb[i + 2], 1.2f, 1e-5) << i / 3;
    }
    EXPECT_EQ(st.primary, 32u * 32u * 4u);
    EXPECT_EQ(st.secondary, 32u * 32u * 4u);  // one diffuse bounce per path
    EXPECT_EQ(st.sanitized, 0u);
}

TEST(PathTracing, AtDepthOneItIsTheRayTracersDirectLight) {
    rt::RenderScene rs = plane_scene(0.8f, {0, 0, 0});
    scene::PointLight l;
    l.position = {1, 3, 0.5};
    l.intensity = 1.5f;
    rs.scene().point_lights = {l};
    rs.update_lights();
    core::RenderParams p = rs.params();
    p.spp = 9;
    const rt::Image whitted = render(rs, p, 24);
    p.path_tracing = 1;
    p.max_path_depth = 1;
    const rt::Image path = render(rs, p, 24);
    for (std::size_t i = 0; i < path.rgb.size(); ++i) ASSERT_NEAR(path.rgb[i], whitted.rgb[i], 1e-5) << i;
    double mean = 0;
    for (float v : path.rgb) mean += v;
    EXPECT_GT(mean / path.rgb.size(), 0.1);  // lit
}

TEST(PathTracing, IndirectLightAddsToDirectLightAndConverges) {
    // A floor and a wall at right angles under one point light: deeper paths add the light the wall
    // throws on the floor; two independent frames of 64 samples agree within the noise.
    auto pts = rect_points({-2, 0, -2}, {4, 0, 0}, {0, 0, 4}, {0, 1, 0}, 120);
    const auto wall = rect_points({-2, 0, -2}, {4, 0, 0}, {0, 4, 0}, {0, 0, 1}, 120);
    pts.insert(pts.end(), wall.begin(), wall.end());
    scene::Scene sc;
    scene::Material m;
    m.specular = {0, 0, 0};
    m.ambient = {0, 0, 0};
    m.point_colors = scene::PointColors::none;
    sc.materials = {m};
    sc.environment.color = {0, 0, 0};
    sc.camera.position = {0, 2, 3};
    sc.camera.look_at = {0, 0, -1};
    scene::PointLight l;
    l.position = {0, 1.5, 1};
    sc.point_lights = {l};
    const rt::RenderScene rs = rt::RenderScene::from_pools(sc, {make_pool(make_model(pts, {0, 0, 0}))});
    core::RenderParams p = rs.params();
    p.path_tracing = 1;
    p.spp = 64;
    p.max_path_depth = 1;
    auto mean = [](const rt::Image& img) {
        double s = 0;
        for (float v : img.rgb) s += v;
        return s / img.rgb.size();
    };
    const double direct = mean(render(rs, p, 16));
    p.max_path_depth = 10;
    const double a = mean(render(rs, p, 16));
    p.frame = 1;
    const double b = mean(render(rs, p, 16));
    EXPECT_GT(a, direct * 1.05);  // the wall lights the floor and back
    EXPECT_NEAR(a, b, 0.03 * a);  // new samples, same estimate
    EXPECT_NE(a, b);              // frames draw new samples
}

TEST(PathTracing, CameraRaysSeeAreaLightsAndDiffuseSurfacesAreLitByThem) {
    rt::RenderScene rs = plane_scene(0.5f, {0, 0, 0});
    scene::AreaLight a;
    a.corner = {-0.2, 1.0, 0.05};  // around (0, 1, 0.25), where the centre ray crosses y = 1
    a.edge_u = {0.4, 0, 0};
    a.edge_v = {0, 0, 0.4};
    a.color = {1, 0.5, 0.25};
    a.intensity = 2;
    a.samples = 4;
    rs.scene().area_lights = {a};
    rs.update_lights();
    core::RenderParams p = rs.params();
    p.path_tracing = 1;
    p.spp = 16;
    const rt::Image img = render(rs, p, 33);
    // The centre pixel looks through the light (between camera and plane): its radiance exactly.
    const std::size_t c = (16 * 33 + 16) * 3;
    EXPECT_NEAR(img.rgb[c + 0], 2.0f, 1e-5);
    EXPECT_NEAR(img.rgb[c + 1], 1.0f, 1e-5);
    EXPECT_NEAR(img.rgb[c + 2], 0.5f, 1e-5);
    // A corner pixel sees the lit plane (direct light; no sky).
    EXPECT_GT(img.rgb[0], 0.05f);
}

}  // namespace
}  // namespace prt::test
