// Every surface through the renderer (render.h closest_hit_scene / occluded, RenderScene loading):
// splats (thesis 3), ISO (thesis 4), MLS (WS05) and Bezier patches (seed 002), on pools made by the
// real tools, checked against analytic geometry computed here: hit distances on a sphere, holes,
// a flat patch's exact plane, mixed scenes (the nearer model wins), mirror patches that never see
// themselves, and shadows cast by every surface.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>
#include <vector>

#include "prt/core/render.h"
#include "prt/runtime/backend.h"
#include "prt/runtime/render_scene.h"
#include "surface_fixtures.h"
#include "window_controls.h"

namespace prt::test {
namespace {

struct SphereErrors {
    std::size_t rays = 0, analytic_hits = 0, holes = 0, extra = 0;
    double max_err = 0;     ///< |t - t_true| over rays both hit, relative to the radius
    double max_normal = 0;  ///< 1 - cos(normal, true normal)
};

/// Primary rays of a w x w camera against the unit sphere at the world origin. Rays within
/// `rim` (relative) of the silhouette are not judged for holes or extra hits.
SphereErrors sphere_errors(const rt::RenderScene& rs, std::uint32_t w, double rim = 0.02) {
    SphereErrors e;
    const core::SceneView s = rs.view();
    scene::Camera c = rs.scene().camera;
    c.width = c.height = w;
    const core::PinholeCamera cam = rs.camera(c);
    const auto& org = rs.render_origin();
    const double center[3] = {-org[0], -org[1], -org[2]};  // the world origin in the render frame
    for (std::uint32_t y = 0; y < w; ++y) {
        for (std::uint32_t x = 0; x < w; ++x) {
            const core::Ray r = core::primary_ray(cam, x, y, w, w);
            const double o[3] = {r.origin.x, r.origin.y, r.origin.z};
            double d[3] = {r.dir.x, r.dir.y, r.dir.z};
            const double dl = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for (double& v : d) v /= dl;
            const double t_true = ray_sphere(o, d, center, 1.0);
            // Distance of the ray from the centre: near 1 is the silhouette.
            const double oc[3] = {center[0] - o[0], center[1] - o[1], center[2] - o[2]};
            const double along = oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2];
            const double miss2 = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - along * along;
            const bool near_rim = std::abs(std::sqrt(std::max(0.0, miss2)) - 1.0) < rim;
            core::SurfaceHit h;
            core::RayCounters cnt;
            const bool hit = core::closest_hit_scene(s, r, h, cnt);
            ++e.rays;
            if (t_true > 0) ++e.analytic_hits;
            if (near_rim) continue;
            if (t_true > 0 && !hit) ++e.holes;
            if (t_true < 0 && hit) ++e.extra;
            if (t_true > 0 && hit) {
                const double t = h.t * dl;  // t is in units of the (unit) render-frame direction
                e.max_err = std::max(e.max_err, std::abs(t - t_true));
                double p[3], n[3] = {h.normal.x, h.normal.y, h.normal.z};
                for (int a = 0; a < 3; ++a) p[a] = o[a] + t_true * d[a] - center[a];
                const double cosine = p[0] * n[0] + p[1] * n[1] + p[2] * n[2];
                e.max_normal = std::max(e.max_normal, 1.0 - cosine);
            }
        }
    }
    return e;
}

class SurfacesTest : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        s_dir = new TempDir("prt-surfaces-test");
        if (surface_tools_built()) s_sphere = sphere_pool_all_surfaces(s_dir->path, 40000);
    }
    void SetUp() override { PRT_SKIP_WITHOUT_SURFACE_TOOLS(); }
    static void TearDownTestSuite() {
        delete s_dir;
        s_dir = nullptr;
    }
    static inline TempDir* s_dir = nullptr;
    static inline std::filesystem::path s_sphere;
};

TEST_F(SurfacesTest, EverySurfaceOfASphereMatchesTheAnalyticSphere) {
    ASSERT_FALSE(HasFatalFailure());
    // Bounds per surface at 40k points (mean spacing ~0.018): splats blend flat disks (thesis 3.3);
    // the ISO interpolates corner values (4.5, default refinement) and the MLS surface is the
    // reference (WS05), the closest to the true sphere.
    const struct {
        const char* surface;
        double t_bound, normal_bound;
    } cases[] = {{"splats", 0.01, 0.02}, {"iso", 0.01, 0.02}, {"mls", 0.003, 0.01}};
    for (const auto& c : cases) {
        SCOPED_TRACE(c.surface);
        rt::LoadOptions lo;
        lo.surface = c.surface;
        const rt::RenderScene rs = rt::RenderScene::from_pool(s_sphere, lo);
        ASSERT_EQ(static_cast<int>(rs.models()[0].view.surface),
                  static_cast<int>(std::string(c.surface) == "splats" ? core::SurfaceKind::splats
                                   : std::string(c.surface) == "iso"  ? core::SurfaceKind::iso
                                                                      : core::SurfaceKind::mls));
        const SphereErrors e = sphere_errors(rs, 96);
        EXPECT_GT(e.analytic_hits, e.rays / 6);
        EXPECT_EQ(e.holes, 0u);
        EXPECT_EQ(e.extra, 0u);
        EXPECT_LT(e.max_err, c.t_bound);
        EXPECT_LT(e.max_normal, c.normal_bound);
    }
}

TEST_F(SurfacesTest, WindowKeyKCyclesTheSurfacesThePoolHolds) {
    ASSERT_FALSE(HasFatalFailure());
    // The window's K (runtime/player/window_controls.h): splats -> iso -> mls -> splats on a pool
    // holding the three; patches are skipped (not in the pool).
    const player::SurfaceReload reload = [](const std::string& surface) {
        rt::LoadOptions lo;
        lo.surface = surface;
        return rt::RenderScene::from_pool(s_sphere, lo);
    };
    std::optional<rt::RenderScene> rs = reload("splats");
    for (const char* expected : {"iso", "mls", "splats"}) {
        rs = player::next_surface(*rs, reload);
        ASSERT_TRUE(rs.has_value()) << expected;
        EXPECT_EQ(scene::surface_name(rs->models()[0].view.surface), expected);
    }
    // A pool with splats only has no other surface.
    const std::filesystem::path splats = s_dir->path / "splats_only.pool";
    must_run("prt-synth", "sphere -n 2000 -q -o " + splats.string(), s_dir->path);
    must_run("prt-radii", splats.string() + " -q -o " + splats.string(), s_dir->path);
    must_run("prt-octree", splats.string() + " -q -o " + splats.string(), s_dir->path);
    const rt::RenderScene only = rt::RenderScene::from_pool(splats);
    EXPECT_FALSE(player::next_surface(only, [&](const std::string& surface) {
                     rt::LoadOptions lo;
                     lo.surface = surface;
                     return rt::RenderScene::from_pool(splats, lo);
                 }).has_value());
}

TEST_F(SurfacesTest, FloatAndQuantizedIsoLeavesBothRender) {
    ASSERT_FALSE(HasFatalFailure());
    for (bool fl : {false, true}) {
        rt::LoadOptions lo;
        lo.surface = "iso";
        lo.iso_float = fl;
        const rt::RenderScene rs = rt::RenderScene::from_pool(s_sphere, lo);
        EXPECT_EQ(rs.models()[0].view.iso.use_q8, fl ? 0u : 1u);
        // Only the leaves traced are kept for the upload.
        EXPECT_EQ(rs.models()[0].view.iso.leaves_f32 == nullptr, !fl);
        const SphereErrors e = sphere_errors(rs, 64);
        EXPECT_EQ(e.holes, 0u);
        EXPECT_LT(e.max_err, 0.01);
    }
}

TEST_F(SurfacesTest, AskingForASurfaceThePoolLacksIsOneLineNamingTheFile) {
    ASSERT_FALSE(HasFatalFailure());
    rt::LoadOptions lo;
    lo.surface = "patches";
    try {
        (void)rt::RenderScene::from_pool(s_sphere, lo);
        FAIL() << "expected an error";
    } catch (const Error& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("sphere.pool"), std::string::npos) << what;
        EXPECT_NE(what.find("prt-patches"), std::string::npos) << what;
        EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
}

TEST_F(SurfacesTest, ShadowsFallFromEverySurface) {
    ASSERT_FALSE(HasFatalFailure());
    // A light straight above the sphere: a shadow ray from (0, -3, 0) upwards is blocked, one from
    // (3, -3, 0) is not, whatever the surface.
    for (const char* surface : {"splats", "iso", "mls"}) {
        SCOPED_TRACE(surface);
        rt::LoadOptions lo;
        lo.surface = surface;
        const rt::RenderScene rs = rt::RenderScene::from_pool(s_sphere, lo);
        const core::SceneView s = rs.view();
        const auto& org = rs.render_origin();
        auto ray_up = [&](double x) {
            core::Ray r{{static_cast<float>(x - org[0]), static_cast<float>(-3 - org[1]),
                         static_cast<float>(-org[2])},
                        {0, 1, 0},
                        6.0f,
                        0};
            return r;
        };
        core::RayCounters c;
        EXPECT_TRUE(core::occluded(s, ray_up(0), c));
        EXPECT_FALSE(core::occluded(s, ray_up(3), c));
        EXPECT_GT(c.leaves, 0u);
    }
}

TEST_F(SurfacesTest, IsoSharedWalkTracesTheSameRaysAsTraceRay) {
    ASSERT_FALSE(HasFatalFailure());
    // The ISO-only kernels with secondary rays, and those without them for frames with shadow rays
    // (k_mask_shadow_walk), trace with trace_ray_shared (render.h: closest hits and shadow rays
    // from one call site); the CPU and every other kernel with trace_ray. Both must give the same
    // image bit for bit and count the same rays: two ISO spheres reflecting each other (one a pure
    // mirror, shaded black), a light with shadow rays and one without; no bounce (the kernel
    // without secondary rays), one and four.
    const scene::Scene sc = mirror_spheres_scene(s_sphere, scene::SurfaceKind::iso);
    rt::RenderScene rs = rt::RenderScene::load(sc);
    constexpr std::uint32_t w = 96, h = 72;
    scene::Camera cam_desc = rs.scene().camera;
    cam_desc.width = w;
    cam_desc.height = h;
    const core::PinholeCamera cam = rs.camera(cam_desc);
    constexpr std::uint32_t k_iso = core::k_mask_iso | core::k_mask_secondary;
    constexpr std::uint32_t k_iso_shadows = core::k_mask_iso | core::k_mask_shadow_walk;
    static_assert(core::k_shared_walk<k_iso> && core::k_shared_walk<k_iso_shadows> &&
                  !core::k_shared_walk<core::k_mask_all> && !core::k_shared_walk<core::k_mask_iso> &&
                  !core::k_shared_walk<core::k_mask_splats | core::k_mask_shadow_walk>);
    for (const std::uint32_t bounces : {0u, 1u, 4u}) {
        SCOPED_TRACE("bounces " + std::to_string(bounces));
        core::SceneView s = rs.view();
        s.params.max_bounces = bounces;
        core::RayCounters ca, cb;
        std::size_t differ = 0, lit = 0;
        for (std::uint32_t y = 0; y < h; ++y) {
            for (std::uint32_t x = 0; x < w; ++x) {
                const core::Vec3 ref = core::render_pixel<core::k_mask_all>(s, cam, x, y, w, h, ca);
                const core::Vec3 got = bounces == 0
                                           ? core::render_pixel<k_iso_shadows>(s, cam, x, y, w, h, cb)
                                           : core::render_pixel<k_iso>(s, cam, x, y, w, h, cb);
                if (std::memcmp(&ref, &got, sizeof ref) != 0) ++differ;
                if (ref.x > 0.0f) ++lit;
            }
        }
        EXPECT_EQ(differ, 0u);
        EXPECT_GT(lit, w * h / 10);
        if (bounces > 0) EXPECT_GT(ca.secondary, 1000u);
        EXPECT_GT(ca.shadow, 500u);
        EXPECT_EQ(ca.secondary, cb.secondary);
        EXPECT_EQ(ca.shadow, cb.shadow);
        EXPECT_EQ(ca.leaves, cb.leaves);
        EXPECT_EQ(ca.primary, cb.primary);
        EXPECT_EQ(ca.dropped, cb.dropped);
    }
}

TEST(Patches, AFlatPatchIsHitOnItsPlaneAndMixesWithPointModels) {
    PRT_SKIP_WITHOUT_SURFACE_TOOLS();
    // prt-patches marks a single patch oriented (no conflicts), so the renderer applies the
    // seamless rule (thesis 3.6): rays from +z see its front face.
    TempDir dir("prt-surfaces-patch");
    // A flat patch z = -2 over [-2, 2]^2 and, in front of it, the unit sphere as splats.
    const auto bpt = flat_patch_file(dir.path, -2, -2, -2, 4);
    const auto patch_pool = dir.path / "flat.pool";
    must_run("prt-patches", bpt.string() + " -o " + patch_pool.string() + " -q", dir.path);
    must_run("prt-synth", "sphere -n 20000 -o " + (dir.path / "s.pool").string() + " -q", dir.path);
    for (const char* t : {"prt-radii", "prt-octree"})
        must_run(t, (dir.path / "s.pool").string() + " -o " + (dir.path / "s.pool").string() + " -q",
                 dir.path);
    ASSERT_FALSE(HasFatalFailure());

    scene::Scene sc;
    sc.materials.push_back(scene::Material{});
    scene::Model patch, ball;
    patch.pool = patch_pool;
    patch.surface = scene::SurfaceKind::patches;
    ball.pool = dir.path / "s.pool";
    sc.models = {patch, ball};
    const rt::RenderScene rs = rt::RenderScene::load(sc);
    ASSERT_EQ(rs.models()[0].view.surface, core::SurfaceKind::patches);
    const core::SceneView s = rs.view();
    const auto& org = rs.render_origin();
    auto shoot = [&](double x, double y, core::SurfaceHit& h) {
        core::Ray r{
            {static_cast<float>(x - org[0]), static_cast<float>(y - org[1]), static_cast<float>(5 - org[2])},
            {0, 0, -1},
            core::k_inf,
            0};
        core::RayCounters c;
        return core::closest_hit_scene(s, r, h, c);
    };
    core::SurfaceHit h;
    // Beside the sphere: the plane at t = 7, exactly (Newton in double, seed 002 3).
    for (double x : {-1.7, 1.3, 1.9}) {
        for (double y : {-1.9, 1.5}) {
            ASSERT_TRUE(shoot(x, y, h)) << x << " " << y;
            EXPECT_EQ(h.model, 0u);
            EXPECT_NEAR(h.t, 7.0, 1e-5);
            EXPECT_NEAR(h.normal.z, 1.0, 1e-6);
        }
    }
    // Through the sphere's centre: the sphere at t = 4 hides the plane.
    ASSERT_TRUE(shoot(0, 0, h));
    EXPECT_EQ(h.model, 1u);
    EXPECT_NEAR(h.t, 4.0, 0.01);
    // Off the patch: nothing.
    EXPECT_FALSE(shoot(2.5, 0, h));
}

TEST(Patches, AMirrorPatchReflectsTheBackgroundNeverItself) {
    PRT_SKIP_WITHOUT_SURFACE_TOOLS();
    TempDir dir("prt-surfaces-mirror");
    const auto bpt = flat_patch_file(dir.path, -1, -1, 0, 2);
    const auto pool_path = dir.path / "m.pool";
    must_run("prt-patches", bpt.string() + " -o " + pool_path.string() + " -q", dir.path);
    ASSERT_FALSE(HasFatalFailure());
    scene::Scene sc;
    scene::Material mirror;
    mirror.reflectivity = 1.0f;
    mirror.diffuse_reflectance = 0.0f;
    sc.materials = {mirror};
    scene::Model m;
    m.pool = pool_path;
    m.surface = scene::SurfaceKind::patches;
    sc.models = {m};
    sc.environment.color = {0.25f, 0.5f, 0.75f};
    sc.camera.position = {0.3, 0.2, 3};
    sc.camera.look_at = {0, 0, 0};
    sc.camera.width = sc.camera.height = 48;
    sc.camera.fov_y_degrees = 30;
    for (bool oriented : {true, false}) {
        SCOPED_TRACE(oriented ? "oriented pool (seamless flags)" : "unoriented (start-point skip)");
        rt::RenderScene rs = rt::RenderScene::load(sc);
        std::vector<core::ModelView> views;
        core::SceneView s = rs.view();
        views.assign(s.models, s.models + s.model_count);
        if (!oriented) views[0].patches.flags &= ~pool::k_patch_oriented;
        s.models = views.data();
        auto backend = rt::make_backend("cpu");
        backend->set_scene(s);
        rt::FrameRequest req;
        req.camera = rs.camera();
        req.params = rs.params();
        req.width = req.height = 48;
        rt::Image img;
        const rt::FrameStats st = backend->render(req, img);
        // Every pixel shows the background: directly, or mirrored once by the patch.
        for (std::size_t i = 0; i < img.rgb.size(); i += 3) {
            ASSERT_NEAR(img.rgb[i + 0], 0.25f, 1e-5) << i / 3;
            ASSERT_NEAR(img.rgb[i + 2], 0.75f, 1e-5) << i / 3;
        }
        EXPECT_GT(st.secondary, 48u * 48u / 4);  // most of the view is the mirror
    }
}

}  // namespace
}  // namespace prt::test
