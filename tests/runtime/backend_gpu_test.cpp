// The CUDA backend against the CPU backend (label gpu): the same scenes, the same core functions,
// images that agree within a stated tolerance. Skips with a message where no CUDA device exists.
//
// Tolerance: the CUDA build uses fast math (approximate division, square root and powf) and fused
// multiply-adds, so ray parameters differ in their last bits; a hit exactly at a splat's rim or a
// blending window's end can then flip, changing isolated pixels. Stated: at least 99% of pixels
// within 0.02 (linear radiance, per channel) and a mean absolute difference below 0.003; ray counts
// within 1%.
#include <gtest/gtest.h>

#include <cmath>

#include "prt/core/splat.h"
#include "prt/runtime/backend.h"
#include "prt/runtime/render_scene.h"
#include "surface_fixtures.h"
#include "test_scene.h"

namespace prt::test {
namespace {

struct GpuScene {
    std::string name;
    rt::RenderScene rs;
};

std::vector<GpuScene> scenes() {
    std::vector<GpuScene> out;
    {
        auto pts = rect_points({-2, 0, -2}, {4, 0, 0}, {0, 0, 4}, {0, 1, 0}, 120, {180, 200, 220, 255});
        const auto ball = sphere_points({0, 1, 0}, 0.5, 8000, false, {230, 120, 60, 255});
        pts.insert(pts.end(), ball.begin(), ball.end());
        scene::Scene sc;
        sc.materials.push_back(scene::Material{});
        sc.camera.position = {0.5, 3, 4};
        sc.camera.look_at = {0, 0.5, 0};
        scene::PointLight pl;
        pl.position = {1.2, 4, 0.6};
        sc.point_lights.push_back(pl);
        sc.materials[0].reflectivity = 0.2f;
        sc.materials[0].diffuse_reflectance = 0.8f;
        out.push_back({"sphere on a plane, shadows, reflections",
                       rt::RenderScene::from_pools(sc, {make_pool(make_model(pts, {0, 0.5, 0}))})});
    }
    {
        auto pts = room_points(-1, 1, 48);
        const auto glass = sphere_points({-0.2, -0.4, -0.3}, 0.4, 12000);
        pts.insert(pts.end(), glass.begin(), glass.end());
        scene::Scene sc;
        sc.materials.push_back(scene::Material{});
        sc.materials[0].reflectivity = 0.4f;
        sc.materials[0].diffuse_reflectance = 0.6f;
        sc.camera.position = {0.5, 0.3, 0.8};
        sc.camera.look_at = {-1, -1, -1};
        sc.camera.fov_y_degrees = 70;
        scene::PointLight pl;
        pl.position = {0.3, 0.8, 0.2};
        sc.point_lights.push_back(pl);
        sc.render.max_bounces = 6;
        out.push_back({"mirror room with a sphere",
                       rt::RenderScene::from_pools(sc, {make_pool(make_model(pts, {0, 0, 0}))})});
    }
    {
        auto pts = rect_points({-2, -1, -2}, {4, 0, 0}, {0, 0, 4}, {0, 1, 0}, 100, {90, 200, 90, 255});
        const auto glass = sphere_points({0, 0, 0}, 0.8, 15000);
        pts.insert(pts.end(), glass.begin(), glass.end());
        scene::Scene sc;
        scene::Material floor;
        scene::Material g;
        g.transmissivity = 0.9f;
        g.reflectivity = 0.1f;
        g.diffuse_reflectance = 0.0f;
        g.refractive_index = 1.5f;
        sc.materials = {floor, g};
        sc.camera.position = {0, 1, 3.5};
        sc.camera.look_at = {0, -0.3, 0};
        scene::PointLight pl;
        pl.position = {2, 4, 2};
        sc.point_lights.push_back(pl);
        sc.render.max_bounces = 8;
        TestModel m = make_model(pts, {0, 0, 0});
        std::vector<std::uint32_t> ids(m.positions.size(), 0);
        for (std::size_t i = m.positions.size() - glass.size(); i < ids.size(); ++i) ids[i] = 1;
        // Rebuild the pool with material ids.
        pool::PoolWriter w;
        const auto base = make_pool(m);  // carry_over() keeps views: the source must outlive serialize()
        w.carry_over(*base);
        w.add_array(pool::SectionType::material_ids, ids);
        auto pf = std::make_shared<const pool::PoolFile>(pool::PoolFile::from_bytes(w.serialize(), "glass"));
        out.push_back({"glass sphere over a plane (refraction, TIR)", rt::RenderScene::from_pools(sc, {pf})});
    }
    {
        // issue 17: the first scene's pool bricked (prt-bricks --keep-float; small bricks, so rays
        // cross many) and traced through its bricks: the bricked-splat kernels (core bricks.h).
        TempDir dir("prt-gpu-bricks");
        write_pool(*out[0].rs.models().at(0).pool, dir.path / "plain.pool");
        const std::string args = (dir.path / "plain.pool").string() + " -o " +
                                 (dir.path / "bricked.pool").string() +
                                 " --keep-float --brick-splats 4000 -q";
        const ToolRun r = run_tool("prt-bricks", args, dir.path);
        if (r.code == 0) {
            rt::LoadOptions lo;
            lo.bricks = true;
            auto pf = std::make_shared<const pool::PoolFile>(pool::PoolFile::open(dir.path / "bricked.pool"));
            out.push_back(
                {"sphere on a plane, bricked", rt::RenderScene::from_pools(out[0].rs.scene(), {pf}, lo)});
        } else {
            ADD_FAILURE() << "prt-bricks: " << r.err;
        }
    }
    return out;
}

/// `bounces`: the frame's bounce limit when not ~0u (0: a frame with no secondary rays, which the
/// CUDA backend renders with its kernels that lack them).
rt::Image render(rt::Backend& b, const rt::RenderScene& rs, std::uint32_t w, std::uint32_t h,
                 rt::FrameStats* stats, std::uint32_t leaf_culling = core::k_cull_slabs,
                 std::uint32_t bounces = ~0u) {
    b.set_scene(rs.view());
    rt::FrameRequest req;
    scene::Camera c = rs.scene().camera;
    c.width = w;
    c.height = h;
    req.camera = rs.camera(c);
    req.params = rs.params();
    req.params.leaf_culling = leaf_culling;
    if (bounces != ~0u) req.params.max_bounces = bounces;
    req.width = w;
    req.height = h;
    rt::Image img;
    *stats = b.render(req, img);
    return img;
}

void compare(const rt::Image& ref, const rt::Image& img, const rt::FrameStats& sref,
             const rt::FrameStats& simg) {
    ASSERT_EQ(ref.rgb.size(), img.rgb.size());
    std::size_t bad = 0;
    double sum = 0;
    for (std::size_t i = 0; i < ref.rgb.size(); i += 3) {
        double worst = 0;
        for (int c = 0; c < 3; ++c) {
            const double d = std::abs(double(ref.rgb[i + c]) - double(img.rgb[i + c]));
            worst = std::max(worst, d);
            sum += d;
        }
        bad += worst > 0.02;
    }
    const std::size_t pixels = ref.rgb.size() / 3;
    EXPECT_LE(bad, pixels / 100) << bad << " of " << pixels << " pixels differ by more than 0.02";
    EXPECT_LT(sum / ref.rgb.size(), 0.003);
    EXPECT_EQ(sref.primary, simg.primary);
    EXPECT_NEAR(double(simg.shadow), double(sref.shadow), 0.01 * double(sref.shadow) + 2);
    EXPECT_NEAR(double(simg.secondary), double(sref.secondary), 0.01 * double(sref.secondary) + 2);
    EXPECT_EQ(simg.sanitized, 0u);
}

std::string backend_case_name(
    const ::testing::TestParamInfo<std::pair<const char*, rt::BackendOptions>>& info) {
    const char* names[] = {"mega_zorder",      "mega_linear",      "mega_static_zorder",
                           "wavefront_zorder", "wavefront_linear", "hybrid"};
    return names[info.index];
}

class GpuAgreement : public ::testing::TestWithParam<std::pair<const char*, rt::BackendOptions>> {};

TEST_P(GpuAgreement, CudaMatchesCpu) {
    const rt::BackendAvailability a = rt::backend_availability();
    if (!a.cuda_device) GTEST_SKIP() << "no CUDA device: " << a.cuda_why;
    const std::string kind = GetParam().first;
    auto cpu = rt::make_backend("cpu");
    auto gpu = rt::make_backend(kind, GetParam().second);
    for (GpuScene& s : scenes()) {
        SCOPED_TRACE(s.name + " on " + gpu->device());
        rt::FrameStats sc, sg;
        const rt::Image ref = render(*cpu, s.rs, 160, 120, &sc);
        const rt::Image img = render(*gpu, s.rs, 160, 120, &sg);
        compare(ref, img, sc, sg);
        EXPECT_GT(sg.secondary, 0u);
        // The same frame without bounces: the kernels without secondary rays (core::spawns_secondary).
        rt::FrameStats dc, dg;
        const rt::Image dref = render(*cpu, s.rs, 160, 120, &dc, core::k_cull_slabs, 0);
        const rt::Image dimg = render(*gpu, s.rs, 160, 120, &dg, core::k_cull_slabs, 0);
        compare(dref, dimg, dc, dg);
        EXPECT_EQ(dg.secondary, 0u);
        EXPECT_GT(dg.shadow, 0u);
    }
}

TEST(GpuLeafCulling, PassingLeavesByTheirBoundsKeepsTheImage) {
    // The per-leaf bounds (core::LeafBounds) on the GPU: the same image as without them (within the
    // fast-math tolerance above), far fewer splat tests, and the CPU backend's counts.
    const rt::BackendAvailability a = rt::backend_availability();
    if (!a.cuda_device) GTEST_SKIP() << "no CUDA device: " << a.cuda_why;
    auto cpu = rt::make_backend("cpu");
    auto gpu = rt::make_backend("cuda");
    for (GpuScene& s : scenes()) {
        SCOPED_TRACE(s.name + " on " + gpu->device());
        rt::FrameStats off, on, cpu_on;
        const rt::Image a_img = render(*gpu, s.rs, 160, 120, &off, core::k_cull_none);
        const rt::Image b_img = render(*gpu, s.rs, 160, 120, &on, core::k_cull_slabs);
        render(*cpu, s.rs, 160, 120, &cpu_on, core::k_cull_slabs);
        compare(a_img, b_img, off, on);
        EXPECT_EQ(off.culled, 0u);
        EXPECT_GT(on.culled, 0u);
        EXPECT_LT(on.splat_tests, off.splat_tests);
        EXPECT_NEAR(double(on.splat_tests), double(cpu_on.splat_tests), 0.01 * double(cpu_on.splat_tests));
    }
}

TEST(GpuSurfaces, IsoMlsAndPatchesMatchTheCpu) {
    // The other surfaces through the same megakernel: a sphere as ISO and as MLS over a splat floor,
    // with shadows and a reflective floor, and a mirror patch beside the sphere.
    const rt::BackendAvailability a = rt::backend_availability();
    if (!a.cuda_device) GTEST_SKIP() << "no CUDA device: " << a.cuda_why;
    PRT_SKIP_WITHOUT_SURFACE_TOOLS();
    TempDir dir("prt-gpu-surfaces");
    const auto sphere = sphere_pool_all_surfaces(dir.path, 40000);
    const auto bpt = flat_patch_file(dir.path, -1.5, -1.5, 0, 3);
    const auto patch_pool = dir.path / "mirror.pool";
    must_run("prt-patches", bpt.string() + " -o " + patch_pool.string() + " -q", dir.path);
    ASSERT_FALSE(HasFatalFailure());
    auto cpu = rt::make_backend("cpu");
    auto gpu = rt::make_backend("cuda");
    for (const char* surface : {"iso", "mls", "splats"}) {
        SCOPED_TRACE(std::string(surface) + " sphere and a mirror patch on " + gpu->device());
        scene::Scene sc;
        scene::Material diffuse, mirror;
        mirror.reflectivity = 0.7f;
        mirror.diffuse_reflectance = 0.3f;
        sc.materials = {diffuse, mirror};
        scene::Model ball, plate;
        ball.pool = sphere;
        ball.surface = std::string(surface) == "iso"   ? scene::SurfaceKind::iso
                       : std::string(surface) == "mls" ? scene::SurfaceKind::mls
                                                       : scene::SurfaceKind::splats;
        plate.pool = patch_pool;
        plate.surface = scene::SurfaceKind::patches;
        plate.material = 1;
        plate.transform.rotate_degrees = {-90, 0, 0};  // the patch's +z normal turns to +y
        plate.transform.translate = {0, -1, 0};
        sc.models = {ball, plate};
        sc.camera.position = {0.5, 1.5, 4};
        sc.camera.look_at = {0, -0.3, 0};
        scene::PointLight pl;
        pl.position = {1.5, 4, 1};
        sc.point_lights.push_back(pl);
        const rt::RenderScene rs = rt::RenderScene::load(sc);
        rt::FrameStats scpu, sgpu;
        const rt::Image ref = render(*cpu, rs, 160, 120, &scpu);
        const rt::Image img = render(*gpu, rs, 160, 120, &sgpu);
        EXPECT_GT(scpu.secondary, 1000u);  // the mirror is in view
        compare(ref, img, scpu, sgpu);
        // The sphere alone (a reflective material): its kind's kernels with and without secondary
        // rays where the backend has them (cuda_backend.cu's kernel_mask), else the general one.
        sc.models = {ball};
        sc.materials = {mirror};
        const rt::RenderScene alone = rt::RenderScene::load(sc);
        for (const std::uint32_t bounces : {0u, 4u}) {
            SCOPED_TRACE("the sphere alone, bounces " + std::to_string(bounces));
            rt::FrameStats acpu, agpu;
            const rt::Image aref = render(*cpu, alone, 160, 120, &acpu, core::k_cull_slabs, bounces);
            const rt::Image aimg = render(*gpu, alone, 160, 120, &agpu, core::k_cull_slabs, bounces);
            EXPECT_EQ(agpu.secondary > 0, bounces > 0);
            EXPECT_GT(agpu.shadow, 1000u);
            compare(aref, aimg, acpu, agpu);
        }
    }
}

TEST(GpuSurfaces, SpheresReflectingEachOtherMatchTheCpu) {
    // ISO alone and splats alone, against the CPU: with secondary rays (bounces 1 and 4) the ISO
    // kernel whose closest hits and shadow rays share one walk (render.h trace_ray_shared) and the
    // splat kernel's trace_ray; without (bounces 0) the ISO kernel for frames with shadow rays
    // (k_mask_shadow_walk, the same loop) and the splat kernel without secondary rays. Two spheres
    // mirror each other (one a pure mirror, shaded black), one light with shadow rays and one
    // without.
    const rt::BackendAvailability a = rt::backend_availability();
    if (!a.cuda_device) GTEST_SKIP() << "no CUDA device: " << a.cuda_why;
    PRT_SKIP_WITHOUT_SURFACE_TOOLS();
    TempDir dir("prt-gpu-mirror-spheres");
    const auto sphere = sphere_pool_all_surfaces(dir.path, 40000);
    ASSERT_FALSE(HasFatalFailure());
    auto cpu = rt::make_backend("cpu");
    auto gpu = rt::make_backend("cuda");
    for (const bool iso : {true, false}) {
        const scene::Scene sc =
            mirror_spheres_scene(sphere, iso ? scene::SurfaceKind::iso : scene::SurfaceKind::splats);
        const rt::RenderScene rs = rt::RenderScene::load(sc);
        for (const std::uint32_t bounces : {0u, 1u, 4u}) {
            SCOPED_TRACE(std::string(iso ? "iso" : "splats") + ", bounces " + std::to_string(bounces) +
                         " on " + gpu->device());
            rt::FrameStats scpu, sgpu;
            const rt::Image ref = render(*cpu, rs, 160, 120, &scpu, core::k_cull_slabs, bounces);
            const rt::Image img = render(*gpu, rs, 160, 120, &sgpu, core::k_cull_slabs, bounces);
            if (bounces > 0) {
                EXPECT_GT(scpu.secondary, 1000u);
            }
            EXPECT_GT(scpu.shadow, 1000u);  // 160 x 120: about twice the CPU test's 96 x 72 count
            compare(ref, img, scpu, sgpu);
            if (!iso) continue;
            // The ISO walk with macro-regions and the one compiled without them (k_mask_plain_walk):
            // the same leaves hold the hits, so the same image to the bit; "auto" runs both in its
            // first frames (WalkChoice) and every frame is that image.
            bool regions = false;
            for (std::uint32_t m = 0; m < rs.view().model_count; ++m)
                regions = regions || rs.view().models[m].iso.tree.macro_regions != nullptr;
            EXPECT_TRUE(regions) << "the ISO has no macro-regions: nothing to choose";
            for (const char* walk : {"regions", "plain", "auto"}) {
                rt::BackendOptions o;
                o.cuda_iso_walk = walk;
                auto g = rt::make_backend("cuda", o);
                g->set_scene(rs.view());
                rt::FrameRequest req;
                scene::Camera c = rs.scene().camera;
                c.width = 160;
                c.height = 120;
                req.camera = rs.camera(c);
                req.params = rs.params();
                req.params.leaf_culling = core::k_cull_slabs;
                req.params.max_bounces = bounces;
                req.width = 160;
                req.height = 120;
                for (int frame = 0; frame < (std::string(walk) == "auto" ? 6 : 1); ++frame) {
                    rt::Image other;
                    const rt::FrameStats s = g->render(req, other);
                    EXPECT_EQ(other.rgb, img.rgb) << "--iso-walk " << walk << ", frame " << frame;
                    EXPECT_EQ(s.shadow, sgpu.shadow);
                    EXPECT_EQ(s.secondary, sgpu.secondary);
                }
            }
        }
    }
}

TEST(GpuMemory, AScenePastFreeGpuMemoryFailsWithTheFigures) {
    // Issue 10: nothing is allocated; the error names the bytes needed and free and what to do.
    const rt::BackendAvailability a = rt::backend_availability();
    if (!a.cuda_device) GTEST_SKIP() << "no CUDA device: " << a.cuda_why;
    // 2^32 - 16 float ISO leaves of 160 B claimed: 687 GB, more than any GPU has (the check must
    // come first: the host array behind the pointer holds one leaf).
    std::vector<pool::IsoLeafF32> one(1);
    core::ModelView mv;
    mv.surface = core::SurfaceKind::iso;
    mv.iso.leaves_f32 = one.data();
    mv.iso.leaf_count = 0xfffffff0u;
    core::Material mat;
    core::SceneView s;
    s.models = &mv;
    s.model_count = 1;
    s.materials = &mat;
    s.material_count = 1;
    auto gpu = rt::make_backend("cuda");
    try {
        gpu->set_scene(s);
        FAIL() << "expected an error";
    } catch (const Error& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("needs 655360 MiB"), std::string::npos) << what;
        EXPECT_NE(what.find("free"), std::string::npos) << what;
        EXPECT_NE(what.find("prt-iso --max-level"), std::string::npos) << what;
        EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
}

TEST(GpuItemOrder, HeavyItemsFirstChangeNoPixel) {
    // The persistent megakernel hands out first the items that were heavy in the previous frame of
    // the same size (cuda_backend.cu, ItemOrder). Frames in that order equal the image-order queue's
    // bit for bit; a frame of another size starts over (its first frame unordered); the order is in
    // use (items handed out first) from the second frame of a size on.
    const rt::BackendAvailability a = rt::backend_availability();
    if (!a.cuda_device) GTEST_SKIP() << "no CUDA device: " << a.cuda_why;
    rt::BackendOptions fifo;
    fifo.cuda_heavy_first = false;
    auto ordered = rt::make_backend("cuda");
    auto plain = rt::make_backend("cuda", fifo);
    std::uint64_t first_total = 0;
    for (GpuScene& s : scenes()) {
        SCOPED_TRACE(s.name + " on " + ordered->device());
        for (const auto& [w, h] : {std::pair{160u, 120u},
                                   {160u, 120u},
                                   {160u, 120u},
                                   {96u, 64u},
                                   {96u, 64u},
                                   {160u, 120u},
                                   {160u, 120u}}) {
            rt::FrameStats so, sp;
            const rt::Image img = render(*ordered, s.rs, w, h, &so);
            const rt::Image ref = render(*plain, s.rs, w, h, &sp);
            ASSERT_EQ(img.rgb.size(), ref.rgb.size());
            EXPECT_EQ(img.rgb, ref.rgb) << w << "x" << h;
            EXPECT_EQ(img.rgba8, ref.rgba8) << w << "x" << h;
            EXPECT_EQ(so.primary, sp.primary);
            EXPECT_EQ(so.shadow, sp.shadow);
            EXPECT_EQ(so.secondary, sp.secondary);
            EXPECT_EQ(sp.heavy_first, 0u);
            first_total += so.heavy_first;
        }
        // the first frame after a size change has no previous frame to order by
        rt::FrameStats s1, s2;
        render(*ordered, s.rs, 64, 48, &s1);
        EXPECT_EQ(s1.heavy_first, 0u);
        render(*ordered, s.rs, 64, 48, &s2);
        EXPECT_LE(s2.heavy_first, std::uint64_t{4 * 3 * 8});  // at most every item of 64x48
    }
    EXPECT_GT(first_total, 0u) << "no frame of any scene handed out heavy items first";
}

rt::BackendOptions opts(bool wavefront, bool linear, bool persistent = true) {
    rt::BackendOptions o;
    o.cuda_wavefront = wavefront;
    o.cuda_linear_mapping = linear;
    o.cuda_persistent = persistent;
    return o;
}

INSTANTIATE_TEST_SUITE_P(Backends, GpuAgreement,
                         ::testing::Values(std::make_pair("cuda", opts(false, false)),
                                           std::make_pair("cuda", opts(false, true)),
                                           std::make_pair("cuda", opts(false, false, false)),
                                           std::make_pair("cuda", opts(true, false)),
                                           std::make_pair("cuda", opts(true, true)),
                                           std::make_pair("hybrid", opts(false, false))),
                         backend_case_name);

}  // namespace
}  // namespace prt::test
