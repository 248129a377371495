// The shared core's ray tracing against analytic geometry (issue 4 tests): hit points on a
// sphere at extreme scales and offsets, shadows of a sphere on a plane, reflections in the
// corners of a closed mirror room (thesis 3.6, fig. 3.12), refraction by Snell's law, total
// internal reflection, Lambert + Phong shading, and "never NaN". References are computed here in
// double precision from the analytic shapes, never from the renderer's output.
#include "prt/core/render.h"

#include <gtest/gtest.h>

#include <cmath>

#include "prt/cpu/cpu_backend.h"
#include "prt/runtime/render_scene.h"
#include "test_scene.h"

namespace prt::test {
namespace {

constexpr double k_pi = 3.14159265358979323846;

scene::Scene basic_scene(const D3& cam_pos, const D3& look_at, std::uint32_t w, std::uint32_t h) {
    scene::Scene s;
    s.materials.push_back(scene::Material{});
    s.camera.position = cam_pos;
    s.camera.look_at = look_at;
    s.camera.width = w;
    s.camera.height = h;
    s.camera.fov_y_degrees = 45;
    return s;
}

D3 world_of(const rt::RenderScene& rs, core::Vec3 p) {
    const auto& o = rs.render_origin();
    return {o[0] + p.x, o[1] + p.y, o[2] + p.z};
}

D3 dv(core::Vec3 v) {
    return {v.x, v.y, v.z};
}

/// Distance from the line through p with unit direction d to point c, and the parameter there.
double line_distance(const D3& p, const D3& d, const D3& c, double& t_closest) {
    t_closest = d3_dot(d3_sub(c, p), d);
    return d3_len(d3_sub(d3_add(p, d3_mul(d, t_closest)), c));
}

struct SphereCase {
    double radius;
    D3 center;
    bool deep;
    const char* name;
};

void PrintTo(const SphereCase& c, std::ostream* os) {
    *os << c.name;
}

class SphereHits : public ::testing::TestWithParam<SphereCase> {};

TEST_P(SphereHits, HitPointsLieOnTheTrueSphere) {
    const SphereCase sc = GetParam();
    const std::size_t n = 20000;
    const auto pts = sphere_points(sc.center, sc.radius, n);
    const double r = pts[0].radius;  // splat radius
    const TestModel model = make_model(pts, sc.center);
    const D3 cam = d3_add(sc.center, {0.3 * sc.radius, 0.5 * sc.radius, 3.0 * sc.radius});
    rt::RenderScene rs = rt::RenderScene::from_pools(basic_scene(cam, sc.center, 64, 64), {make_pool(model)});
    core::SceneView view = rs.view();
    view.params.deep_blending = sc.deep ? 1u : 0u;
    const core::PinholeCamera pc = rs.camera();
    // Any point of a disk tangent to the sphere lies between R and sqrt(R^2 + r^2) from its centre.
    const double outer = std::sqrt(sc.radius * sc.radius + r * r) - sc.radius;
    const double fuzz = 2e-6 * sc.radius;  // float rounding of positions relative to the model
    int hits = 0, sure_hits = 0, holes = 0, ghosts = 0;
    double worst_out = 0, worst_in = 0, worst_angle = 0;
    for (std::uint32_t y = 0; y < 64; ++y) {
        for (std::uint32_t x = 0; x < 64; ++x) {
            const core::Ray ray = core::primary_ray(pc, x, y, 64, 64);
            // The true sphere: impact parameter of the world-frame ray (double).
            const D3 origin = world_of(rs, ray.origin);
            double tc;
            const double b = line_distance(origin, d3_norm(dv(ray.dir)), sc.center, tc);
            core::SurfaceHit h;
            core::RayCounters c;
            const bool hit = core::closest_hit_scene(view, ray, h, c);
            if (b < sc.radius - 2 * r) {
                ++sure_hits;
                if (!hit) ++holes;
            }
            if (b > sc.radius + 2 * r && hit) ++ghosts;
            if (!hit) continue;
            ++hits;
            const D3 p = world_of(rs, h.position);
            const double dist = d3_len(d3_sub(p, sc.center)) - sc.radius;
            worst_out = std::max(worst_out, dist);
            worst_in = std::min(worst_in, dist);
            const D3 true_n = d3_norm(d3_sub(p, sc.center));
            const double cosang = std::clamp(d3_dot(true_n, d3_norm(dv(h.normal))), -1.0, 1.0);
            worst_angle = std::max(worst_angle, std::acos(cosang));
        }
    }
    SCOPED_TRACE(sc.name);
    EXPECT_GT(sure_hits, 500) << "the sphere should cover much of the image";
    EXPECT_EQ(holes, 0) << "rays through the sphere's interior missed it";
    EXPECT_EQ(ghosts, 0) << "rays well outside the sphere hit something";
    EXPECT_LE(worst_out, outer + fuzz) << "hit point farther out than any tangent disk reaches";
    EXPECT_GE(worst_in, -fuzz) << "hit point inside the sphere";
    // Disks blended at a hit have centres within about r of it: their normals differ from the true
    // one by at most about r / R radians.
    EXPECT_LE(worst_angle, 1.5 * r / sc.radius) << "blended normal too far from the true normal";
}

INSTANTIATE_TEST_SUITE_P(
    Extremes, SphereHits,
    ::testing::Values(SphereCase{1.0, {0, 0, 0}, false, "unit sphere at the origin"},
                      SphereCase{1.0, {0, 0, 0}, true, "unit sphere, deep blending"},
                      SphereCase{1e-4, {1e6, -1e6, 1e6}, false, "1e-4 sphere 1e6 from the origin"},
                      SphereCase{1e6, {1e6, 1e6, -1e6}, false, "1e6 sphere 1e6 from the origin"},
                      SphereCase{1e6, {3e6, 1e6, -1e6}, true, "1e6 sphere, deep blending"}),
    [](const auto& info) { return std::string("case") + std::to_string(info.index); });

TEST(Shadows, SphereShadowOnPlaneWhereGeometrySays) {
    auto floor = rect_points({-2, 0, -2}, {4, 0, 0}, {0, 0, 4}, {0, 1, 0}, 160);
    const double R = 0.5;
    const D3 c{0, 1, 0};
    const auto ball = sphere_points(c, R, 8000);
    const double r_ball = ball[0].radius;
    floor.insert(floor.end(), ball.begin(), ball.end());
    const TestModel model = make_model(floor, {0, 0.5, 0});
    scene::Scene sc = basic_scene({0.5, 6, 3}, {0.3, 0, 0.1}, 64, 64);
    const D3 light{1.2, 4, 0.6};
    scene::PointLight pl;
    pl.position = light;
    sc.point_lights.push_back(pl);
    rt::RenderScene rs = rt::RenderScene::from_pools(sc, {make_pool(model)});
    const core::SceneView view = rs.view();
    const core::PinholeCamera pc = rs.camera();
    int shadowed = 0, lit = 0, wrong = 0;
    for (std::uint32_t y = 0; y < 64; ++y) {
        for (std::uint32_t x = 0; x < 64; ++x) {
            const core::Ray ray = core::primary_ray(pc, x, y, 64, 64);
            core::SurfaceHit h;
            core::RayCounters cnt;
            if (!core::closest_hit_scene(view, ray, h, cnt)) continue;
            const D3 p = world_of(rs, h.position);
            if (std::abs(p[1]) > 1e-4) continue;  // not the floor
            // Geometry: the segment p -> light passes through the sphere.
            const D3 to_light = d3_sub(light, p);
            const double len = d3_len(to_light);
            double tc;
            const double dmin = line_distance(p, d3_mul(to_light, 1.0 / len), c, tc);
            if (std::abs(dmin - R) < 2.5 * r_ball) continue;  // the splat silhouette's fuzzy band
            const bool truth = dmin < R && tc > 0 && tc < len;
            const core::Vec3 l =
                core::normalize(core::vec3(float(to_light[0]), float(to_light[1]), float(to_light[2])));
            const core::Vec3 lp = view.lights[0].position - h.position;
            const bool occ =
                core::occluded(view, core::Ray{h.position, core::normalize(lp), core::length(lp), 0u}, cnt);
            (void)l;
            if (occ != truth) ++wrong;
            (truth ? shadowed : lit)++;
            // The shaded color agrees: in shadow only the ambient term remains.
            const core::Vec3 col = core::shade_hit(view, ray, h, cnt);
            const core::Material& m = view.materials[h.material];
            const core::Vec3 ambient = m.ambient * h.base_color * m.diffuse_reflectance;
            if (occ)
                EXPECT_NEAR(col.y, ambient.y, 1e-6);
            else
                EXPECT_GT(col.y, ambient.y + 0.05f);
        }
    }
    EXPECT_GT(shadowed, 20) << "the test view should contain the shadow";
    EXPECT_GT(lit, 200);
    EXPECT_EQ(wrong, 0) << "shadow rays disagree with the geometry";
}

/// Linear images of a room of mirrors seen from inside against a bright blue background.
rt::Image mirror_room(int skip_wall) {
    const TestModel model = make_model(room_points(-1, 1, 48, skip_wall), {0, 0, 0});
    scene::Scene sc = basic_scene({0.5, 0.3, 0.6}, {-1, -1, -1}, 48, 48);
    sc.camera.fov_y_degrees = 70;
    sc.materials[0].reflectivity = 0.5f;
    sc.materials[0].diffuse_reflectance = 0.5f;
    sc.environment.color = {0, 0, 1};
    sc.environment.intensity = 50;
    sc.render.max_bounces = 4;
    rt::RenderScene rs = rt::RenderScene::from_pools(sc, {make_pool(model)});
    auto backend = cpu::make_cpu_backend(0);
    backend->set_scene(rs.view());
    rt::FrameRequest req;
    req.camera = rs.camera();
    req.params = rs.params();
    req.width = req.height = 48;
    rt::Image img;
    backend->render(req, img);
    return img;
}

TEST(Reflections, MirrorRoomCornersShowReflectionsNotBackground) {
    // thesis 3.6, fig. 3.12: reflected rays leaving a wall near a corner hit the neighbouring wall
    // within a tiny distance. With the seamless front/back flag they register that hit; a
    // minimum-distance trick would skip it and see the background. In a closed room no ray may
    // escape, so no pixel may carry the background's blue.
    const rt::Image closed = mirror_room(-1);
    double worst = 0;
    for (std::size_t i = 0; i < closed.rgb.size(); i += 3)
        worst = std::max(worst, double(closed.rgb[i + 2] - closed.rgb[i]));
    EXPECT_LT(worst, 1e-4) << "a ray escaped the closed mirror room";
    // Control: open the wall behind the camera (+z): reflections of the opening must show blue,
    // so the check above can fail.
    const rt::Image open = mirror_room(5);
    int blue = 0;
    for (std::size_t i = 0; i < open.rgb.size(); i += 3) blue += open.rgb[i + 2] - open.rgb[i] > 0.1f;
    EXPECT_GT(blue, 50);
}

TEST(Reflections, FramesWithoutSecondaryRaysTraceTheSameWithoutTheirCode) {
    // trace_ray without k_mask_secondary (the CUDA backend's kernels for frames that spawn no
    // reflected or refracted ray) must give those frames the full code's image and counters, and
    // spawns_secondary must say which frames those are.
    const TestModel model = make_model(room_points(-1, 1, 40, -1), {0, 0, 0});
    scene::Scene sc = basic_scene({0.5, 0.3, 0.6}, {-1, -1, -1}, 24, 24);
    sc.materials[0].reflectivity = 0.5f;
    sc.render.max_bounces = 4;
    scene::PointLight pl;
    pl.position = {0.2, 0.4, 0.1};
    sc.point_lights.push_back(pl);
    rt::RenderScene rs = rt::RenderScene::from_pools(sc, {make_pool(model)});
    core::SceneView view = rs.view();
    const core::SecondaryMaterials mats = core::secondary_materials(view.materials, view.material_count);
    EXPECT_TRUE(mats.reflective);
    EXPECT_FALSE(mats.transmissive);
    constexpr std::uint32_t k_direct = core::k_mask_all & ~std::uint32_t{core::k_mask_secondary};
    // {max_bounces, reflections, refractions, shadows} -> spawns secondary rays
    struct Case {
        std::uint32_t bounces, reflections, refractions, shadows;
        bool spawns;
    };
    for (const Case& k : {Case{4, 1, 1, 1, true}, Case{0, 1, 1, 1, false}, Case{4, 0, 1, 1, false},
                          Case{4, 0, 1, 0, false}, Case{2, 1, 0, 0, true}}) {
        view.params.max_bounces = k.bounces;
        view.params.reflections = k.reflections;
        view.params.refractions = k.refractions;
        view.params.shadows = k.shadows;
        EXPECT_EQ(core::spawns_secondary(view.params, mats), k.spawns) << k.bounces << k.reflections;
        int differ = 0;
        core::RayCounters full_c, direct_c;
        for (std::uint32_t y = 0; y < 24; ++y)
            for (std::uint32_t x = 0; x < 24; ++x) {
                const core::Ray r = core::primary_ray(rs.camera(), x, y, 24, 24);
                const core::Vec3 a = core::trace_ray(view, r, full_c);
                const core::Vec3 b = core::trace_ray<k_direct>(view, r, direct_c);
                differ += a.x != b.x || a.y != b.y || a.z != b.z;
            }
        if (k.spawns) {
            EXPECT_GT(differ, 100) << "the reflections should show: the check could not fail";
            EXPECT_GT(full_c.secondary, 0u);
        } else {
            EXPECT_EQ(differ, 0) << k.bounces << " bounces, reflections " << k.reflections;
            EXPECT_EQ(full_c.shadow, direct_c.shadow);
            EXPECT_EQ(full_c.leaves, direct_c.leaves);
            EXPECT_EQ(full_c.splat_tests, direct_c.splat_tests);
        }
        EXPECT_EQ(direct_c.secondary, 0u);
        EXPECT_EQ(full_c.primary, direct_c.primary);
    }
    // A transmissive material spawns refracted rays with refractions on, reflections off.
    core::Material glass = view.materials[0];
    glass.reflectivity = 0;
    glass.transmissivity = 1;
    const core::SecondaryMaterials g = core::secondary_materials(&glass, 1);
    EXPECT_FALSE(g.reflective);
    EXPECT_TRUE(g.transmissive);
    view.params.max_bounces = 1;
    view.params.reflections = 0;
    view.params.refractions = 1;
    EXPECT_TRUE(core::spawns_secondary(view.params, g));
    EXPECT_FALSE(core::spawns_secondary(view.params, core::secondary_materials(nullptr, 0)));
}

struct GlassSphere {
    rt::RenderScene rs;
    double r_over_R;
};

GlassSphere glass_sphere(float ior) {
    const auto pts = sphere_points({0, 0, 0}, 1.0, 30000);
    scene::Scene sc = basic_scene({0, 0, 5}, {0, 0, 0}, 8, 8);
    sc.materials[0].transmissivity = 1.0f;
    sc.materials[0].reflectivity = 0.0f;
    sc.materials[0].diffuse_reflectance = 0.0f;
    sc.materials[0].refractive_index = ior;
    GlassSphere g{rt::RenderScene::from_pools(sc, {make_pool(make_model(pts, {0, 0, 0}))}), pts[0].radius};
    return g;
}

double angle_between(const D3& a, const D3& b) {
    return std::acos(std::clamp(d3_dot(d3_norm(a), d3_norm(b)), -1.0, 1.0));
}

TEST(Refraction, ThroughASphereBendsAsSnellSays) {
    const double n = 1.5;
    GlassSphere g = glass_sphere(static_cast<float>(n));
    const core::SceneView view = g.rs.view();
    for (double b : {0.25, 0.5, 0.7, 0.85}) {
        SCOPED_TRACE("impact parameter " + std::to_string(b));
        const core::Ray in{{static_cast<float>(b), 0, 5}, {0, 0, -1}, core::k_inf, 0u};
        core::SurfaceHit h1, h2;
        core::RayCounters c;
        ASSERT_TRUE(core::closest_hit_scene(view, in, h1, c));
        core::PendingRay spawned[2];
        ASSERT_EQ(core::spawn_secondary(view, core::PendingRay{in, {1, 1, 1}, 0}, h1, spawned), 1u);
        const core::PendingRay inside = spawned[0];
        EXPECT_TRUE(core::ray_inside(inside.ray)) << "refraction must flip the seamless flag";
        // Snell at the entry point (true normal there, double precision).
        const double ti = std::asin(b), tt = std::asin(b / n);
        const D3 d1_true{-std::sin(ti - tt), 0, -std::cos(ti - tt)};
        EXPECT_LT(angle_between(dv(inside.ray.dir), d1_true), 1.5 * g.r_over_R);
        ASSERT_TRUE(core::closest_hit_scene(view, inside.ray, h2, c));
        EXPECT_GT(core::dot(inside.ray.dir, h2.normal), 0.0f) << "the inside ray must hit a back face";
        ASSERT_EQ(core::spawn_secondary(view, inside, h2, spawned), 1u);
        const core::PendingRay out = spawned[0];
        EXPECT_FALSE(core::ray_inside(out.ray));
        // A sphere deviates the ray by 2 (theta_i - theta_t) towards its axis.
        const double dev = 2.0 * (ti - tt);
        const D3 d2_true{-std::sin(dev), 0, -std::cos(dev)};
        EXPECT_LT(angle_between(dv(out.ray.dir), d2_true), 3.0 * g.r_over_R);
        EXPECT_GT(dev, 3.0 * g.r_over_R) << "the deviation itself must be measurable";
    }
}

TEST(Refraction, TotalInternalReflection) {
    GlassSphere g = glass_sphere(1.5f);
    const core::SceneView view = g.rs.view();
    // From inside, hitting the surface at asin(0.9) = 64 degrees > the critical 41.8 degrees.
    const core::Ray r{{0.9f, 0, 0}, {0, 0, 1}, core::k_inf, core::k_ray_inside};
    core::SurfaceHit h;
    core::RayCounters c;
    ASSERT_TRUE(core::closest_hit_scene(view, r, h, c));
    core::PendingRay spawned[2];
    ASSERT_EQ(core::spawn_secondary(view, core::PendingRay{r, {1, 1, 1}, 0}, h, spawned), 1u);
    EXPECT_TRUE(core::ray_inside(spawned[0].ray)) << "a reflected ray stays inside";
    EXPECT_NEAR(spawned[0].weight.x, 1.0f, 1e-6f) << "the transmitted share goes into the reflection";
    // Mirror of (0,0,1) about the true normal at (0.9, 0, sqrt(0.19)).
    const D3 nrm{0.9, 0, std::sqrt(0.19)};
    const D3 d{0, 0, 1};
    const D3 refl = d3_sub(d, d3_mul(nrm, 2 * d3_dot(d, nrm)));
    EXPECT_LT(angle_between(dv(spawned[0].ray.dir), refl), 3.0 * g.r_over_R);
    // Below the critical angle the same material refracts out.
    const core::Ray r2{{0.3f, 0, 0}, {0, 0, 1}, core::k_inf, core::k_ray_inside};
    ASSERT_TRUE(core::closest_hit_scene(view, r2, h, c));
    ASSERT_EQ(core::spawn_secondary(view, core::PendingRay{r2, {1, 1, 1}, 0}, h, spawned), 1u);
    EXPECT_FALSE(core::ray_inside(spawned[0].ray));
}

TEST(Shading, LambertPlusPhongOnAPlane) {
    // A plane z = 0 facing +z: every disk has the same normal, so shading is exact.
    const TestModel model = make_model(
        rect_points({-1, -1, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0, 1}, 64, {255, 128, 64, 255}), {0, 0, 0});
    scene::Scene sc = basic_scene({0, 0, 3}, {0, 0, 0}, 9, 9);
    scene::Material& m = sc.materials[0];
    m.ambient = {0.1f, 0.1f, 0.1f};
    m.diffuse = {0.7f, 0.6f, 0.5f};
    m.specular = {0.3f, 0.3f, 0.3f};
    m.specular_exponent = 20;
    m.diffuse_reflectance = 0.9f;
    scene::PointLight pl;
    pl.position = {1.0, 0.5, 2.0};
    pl.color = {1.0f, 0.9f, 0.8f};
    pl.intensity = 1.5f;
    sc.point_lights.push_back(pl);
    rt::RenderScene rs = rt::RenderScene::from_pools(sc, {make_pool(model)});
    const core::SceneView view = rs.view();
    core::RayCounters c;
    const core::Vec3 col = core::render_pixel(view, rs.camera(), 4, 4, 9, 9, c);  // centre: hits (0,0,0)
    // Reference in double: base color is the sRGB point color decoded.
    auto decode = [](double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); };
    const D3 base{decode(1.0), decode(128 / 255.0), decode(64 / 255.0)};
    const D3 p{0, 0, 0}, nrm{0, 0, 1}, view_dir{0, 0, -1};
    const D3 l = d3_norm(d3_sub(pl.position, p));
    const double ndl = d3_dot(nrm, l);
    const D3 refl = d3_sub(d3_mul(nrm, 2 * ndl), l);
    const double spec = std::pow(std::max(0.0, -d3_dot(refl, view_dir)), 20.0);
    const double expect[3] = {0.9 * (0.1 * base[0] + 1.5 * 1.0 * (0.7 * base[0] * ndl + 0.3 * spec)),
                              0.9 * (0.1 * base[1] + 1.5 * 0.9 * (0.6 * base[1] * ndl + 0.3 * spec)),
                              0.9 * (0.1 * base[2] + 1.5 * 0.8 * (0.5 * base[2] * ndl + 0.3 * spec))};
    EXPECT_NEAR(col.x, expect[0], 2e-4);
    EXPECT_NEAR(col.y, expect[1], 2e-4);
    EXPECT_NEAR(col.z, expect[2], 2e-4);
    EXPECT_EQ(c.primary, 1u);
    EXPECT_EQ(c.shadow, 1u);
}

TEST(Robustness, OutputIsNeverNaN) {
    // Degenerate splats (zero normal, zero radius, NaN position) and a NaN background.
    std::vector<pool::Splat> splats;
    splats.push_back({{0, 0, 0}, 0.5f, {0, 0, 0}, 0});
    splats.push_back({{0.1f, 0, 0}, 0.0f, {0, 0, 1}, 1});
    splats.push_back({{std::nanf(""), 0, 0}, 0.5f, {0, 0, 1}, 2});
    splats.push_back({{0, 0.2f, 0}, 0.3f, {0, 0, 1}, 3});
    const TestOctree tree = build_test_octree(splats, {-1, -1, -1}, 2.0, 1, 4);
    core::ModelView mv;
    mv.octree = tree.view();
    core::Material mat;
    core::PointLight light;
    light.position = {0, 0, 1};
    core::SceneView view;
    view.models = &mv;
    view.model_count = 1;
    view.materials = &mat;
    view.material_count = 1;
    view.lights = &light;
    view.light_count = 1;
    view.environment.color = {std::nanf(""), 0, 0};
    const core::PinholeCamera cam = core::make_pinhole({0, 0, 3}, {0, 0, 0}, {0, 1, 0}, 40, 16, 16);
    auto backend = cpu::make_cpu_backend(1);
    backend->set_scene(view);
    rt::FrameRequest req;
    req.camera = cam;
    req.params = view.params;
    req.width = req.height = 16;
    rt::Image img;
    const rt::FrameStats s = backend->render(req, img);
    for (float v : img.rgb) ASSERT_TRUE(std::isfinite(v));
    // Every pixel that misses the one valid splat sees the NaN background: replaced and counted.
    EXPECT_GT(s.sanitized, 100u) << "NaN background pixels must be counted";
    EXPECT_LT(s.sanitized, 250u) << "the valid splat must still be seen";
    // Pixels on the valid splat are lit (not black).
    const std::size_t centre = (8 * 16 + 8) * 3;
    EXPECT_GT(img.rgb[centre + 1], 0.1f);
}

TEST(CpuBackend, ThreadCountDoesNotChangeTheImage) {
    const TestModel model = make_model(sphere_points({0, 0, 0}, 1.0, 5000), {0, 0, 0});
    scene::Scene sc = basic_scene({0.5, 1, 3}, {0, 0, 0}, 40, 30);
    scene::PointLight pl;
    pl.position = {2, 3, 2};
    sc.point_lights.push_back(pl);
    sc.materials[0].reflectivity = 0.3f;
    rt::RenderScene rs = rt::RenderScene::from_pools(sc, {make_pool(model)});
    rt::Image a, b;
    rt::FrameStats sa, sb;
    for (unsigned threads : {1u, 3u}) {
        auto backend = cpu::make_cpu_backend(threads);
        backend->set_scene(rs.view());
        rt::FrameRequest req;
        req.camera = rs.camera();
        req.params = rs.params();
        req.width = 40;
        req.height = 30;
        (threads == 1 ? sa : sb) = backend->render(req, threads == 1 ? a : b);
    }
    EXPECT_EQ(a.rgb, b.rgb);
    EXPECT_EQ(a.rgba8, b.rgba8);
    EXPECT_EQ(sa.rays(), sb.rays());
    EXPECT_EQ(sa.primary, 1200u);
    EXPECT_GT(sa.shadow, 100u);
    EXPECT_GT(sa.secondary, 100u);
}

}  // namespace
}  // namespace prt::test
