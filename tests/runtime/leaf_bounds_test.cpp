// Per-leaf bounds (core::LeafBounds, rt::build_leaf_bounds, core::leaf_may_hit): rays pass filled
// leaves unread when the leaf's normal cone holds no face they accept (thesis 3.6) or they do not
// cross its slab inside the leaf. The tests: the bounds are conservative against a brute-force
// intersection of every splat (random disks, rays and ranges, inside and outside rays, small and
// far-off models); they do pass what they should (rays leaving a flat surface); and whole images
// (shadows, mirrors, refraction through glass) are bit-identical with and without them.
#include "prt/runtime/leaf_bounds.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "prt/core/leaf_bounds.h"
#include "prt/core/render.h"
#include "prt/cpu/cpu_backend.h"
#include "prt/runtime/render_scene.h"
#include "test_scene.h"

namespace prt::test {
namespace {

/// One leaf of `splats` (leaf_info = {0, n}), its bounds built by the runtime.
struct OneLeaf {
    std::vector<pool::Splat> splats;
    std::vector<std::uint32_t> leaf_info;
    core::OctreeView view;
    core::LeafBounds bounds;
    core::BrickLeafBounds compact;  // a brick leaf's 16 bytes, over the same splats

    explicit OneLeaf(std::vector<pool::Splat> s) : splats(std::move(s)), leaf_info{0, 0} {
        leaf_info[1] = static_cast<std::uint32_t>(splats.size());
        view.leaf_info = leaf_info.data();
        view.filled_leaves = 1;
        view.splats = splats.data();
        view.splat_count = static_cast<std::uint32_t>(splats.size());
        bounds = rt::build_leaf_bounds(view, 1).at(0);
        compact = core::brick_leaf_bounds_of(core::SplatArray{splats.data()}, 0, view.splat_count);
    }
};

core::Vec3 random_unit(std::mt19937& rng) {
    std::normal_distribution<float> g;
    for (;;) {
        const core::Vec3 v{g(rng), g(rng), g(rng)};
        if (core::length2(v) > 1e-6f) return core::normalize(v);
    }
}

/// Splats around `centre` (spread `size`), normals within `spread` radians of `axis` (pi: any).
std::vector<pool::Splat> random_splats(std::mt19937& rng, core::Vec3 centre, float size, core::Vec3 axis,
                                       float spread, int n) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<pool::Splat> out;
    std::uniform_real_distribution<float> u01(0.0f, 1.0f);
    while (static_cast<int>(out.size()) < n) {
        // Narrow spreads: the axis tilted by a random vector (rejection would rarely succeed).
        const core::Vec3 nrm =
            spread < 1.0f ? core::normalize(axis + random_unit(rng) * (spread * u01(rng))) : random_unit(rng);
        if (std::acos(std::clamp(core::dot(nrm, axis), -1.0f, 1.0f)) > spread) continue;
        pool::Splat s{};
        const core::Vec3 p = centre + core::Vec3{u(rng), u(rng), u(rng) * 0.2f} * size;
        s.position = pool::Float3{p.x, p.y, p.z};
        s.radius = size * (0.2f + 0.3f * (u(rng) + 1.0f));
        s.normal = pool::Float3{nrm.x, nrm.y, nrm.z};
        out.push_back(s);
    }
    return out;
}

struct BoundsCase {
    const char* name;
    float scale;   // model size
    float offset;  // distance of the leaf from the local origin
    float spread;  // normal spread, radians
};

void PrintTo(const BoundsCase& c, std::ostream* os) {
    *os << c.name;
}

class LeafBoundsConservative : public ::testing::TestWithParam<BoundsCase> {};

TEST_P(LeafBoundsConservative, NeverPassesALeafHoldingAnAcceptedHit) {
    const BoundsCase c = GetParam();
    std::mt19937 rng(1234);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    int accepted_leaves = 0, passed = 0, compact_passed = 0, rays = 0;
    for (int leaf = 0; leaf < 60; ++leaf) {
        const core::Vec3 centre{c.offset + u(rng) * c.scale, u(rng) * c.scale, u(rng) * c.scale};
        const OneLeaf L(random_splats(rng, centre, c.scale * 0.05f, random_unit(rng), c.spread, 24));
        for (int k = 0; k < 400; ++k) {
            // Rays from near the leaf (some starting on a splat, like secondary rays) and from afar.
            const float reach = (k % 3 == 0 ? 0.05f : (k % 3 == 1 ? 1.0f : 50.0f)) * c.scale;
            core::Vec3 o = centre + random_unit(rng) * reach * std::abs(u(rng));
            if (k % 7 == 0) o = core::vec3(L.splats[k % L.splats.size()].position);
            const core::Vec3 d =
                random_unit(rng) * (0.5f + std::abs(u(rng)));  // not unit, as in model frames
            const bool inside = k % 2 == 1;
            float t_lo = 0.0f, t_hi = core::k_inf;
            if (k % 5 != 0) {
                const float a = std::abs(u(rng)) * reach * 3.0f, b = std::abs(u(rng)) * reach * 3.0f;
                t_lo = std::min(a, b);
                t_hi = std::max(a, b);
            }
            bool any = false;
            for (const pool::Splat& s : L.splats) {
                float t, xr;
                any = any || core::intersect_splat(s, o, d, inside, t_lo, t_hi, t, xr);
            }
            const float inv_dlen = 1.0f / core::length(d);
            for (std::uint32_t mode : {core::k_cull_cones, core::k_cull_slabs}) {
                const bool may = core::leaf_may_hit(L.bounds, o, d, inv_dlen, inside, t_lo, t_hi, mode);
                if (any) {
                    ASSERT_TRUE(may) << "leaf " << leaf << " ray " << k << " mode " << mode
                                     << ": bounds pass a leaf with an accepted hit";
                }
                passed += !may;
                // The compact bounds (integer axis, no range) are as conservative.
                const bool may16 =
                    core::brick_leaf_may_hit(L.compact, o, d, inv_dlen, inside, t_lo, t_hi, mode);
                if (any) {
                    ASSERT_TRUE(may16) << "leaf " << leaf << " ray " << k << " mode " << mode
                                       << ": compact bounds pass a leaf with an accepted hit";
                }
                compact_passed += !may16;
            }
            accepted_leaves += any;
            ++rays;
        }
    }
    EXPECT_GT(accepted_leaves, rays / 50) << "too few hits: the test would prove nothing";
    EXPECT_GT(passed, rays / 4) << "the bounds pass almost nothing";
    // Quantizing the axis to 16 bits costs a little tightness only.
    EXPECT_GE(compact_passed, passed * 0.98) << "compact " << compact_passed << " float " << passed;
}

INSTANTIATE_TEST_SUITE_P(Cases, LeafBoundsConservative,
                         ::testing::Values(BoundsCase{"flat", 1.0f, 0.0f, 0.05f},
                                           BoundsCase{"curved", 1.0f, 0.0f, 0.8f},
                                           BoundsCase{"any_normal", 1.0f, 0.0f, 3.2f},
                                           BoundsCase{"tiny_far", 1e-4f, 3.0f, 0.5f},
                                           BoundsCase{"huge", 1e5f, 2e5f, 0.5f}),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(LeafBounds, RaysLeavingAFlatSurfacePassItsLeaves) {
    // A plane z = 0 facing +z: a secondary ray leaving it upwards (outside ray) or a shadow ray
    // from it accepts none of its front faces; a ray coming down does.
    std::vector<pool::Splat> s;
    for (int i = 0; i < 16; ++i) {
        pool::Splat p{};
        p.position = pool::Float3{0.1f * (i % 4), 0.1f * (i / 4), 0.0f};
        p.radius = 0.08f;
        p.normal = pool::Float3{0, 0, 1};
        s.push_back(p);
    }
    const OneLeaf L(s);
    const core::Vec3 o{0.15f, 0.15f, 0.0f};
    EXPECT_FALSE(core::leaf_may_hit(L.bounds, o, core::normalize(core::Vec3{0.3f, 0.2f, 1.0f}), 1.0f, false,
                                    0.0f, core::k_inf, core::k_cull_cones));
    EXPECT_TRUE(core::leaf_may_hit(L.bounds, o + core::Vec3{0, 0, 1}, core::Vec3{0, 0, -1}, 1.0f, false, 0.0f,
                                   core::k_inf, core::k_cull_cones));
    // Slab: a downward ray whose leaf range ends before the plane cannot hit it.
    EXPECT_FALSE(core::leaf_may_hit(L.bounds, o + core::Vec3{0, 0, 1}, core::Vec3{0, 0, -1}, 1.0f, false,
                                    0.0f, 0.5f, core::k_cull_slabs));
    EXPECT_TRUE(core::leaf_may_hit(L.bounds, o + core::Vec3{0, 0, 1}, core::Vec3{0, 0, -1}, 1.0f, false, 0.5f,
                                   1.5f, core::k_cull_slabs));
    EXPECT_EQ(L.bounds.begin, 0u);
    EXPECT_EQ(L.bounds.end, 16u);
}

/// Renders `rs` on the CPU with the given leaf culling mode.
rt::Image render(const rt::RenderScene& rs, core::RenderParams p, std::uint32_t culling,
                 rt::FrameStats* stats) {
    auto backend = cpu::make_cpu_backend(2);
    backend->set_scene(rs.view());
    p.leaf_culling = culling;
    rt::FrameRequest req;
    req.camera = rs.camera();
    req.params = p;
    req.width = rs.scene().camera.width;
    req.height = rs.scene().camera.height;
    rt::Image img;
    img.resize(req.width, req.height);
    *stats = backend->render(req, img);
    return img;
}

void expect_same_images(const rt::RenderScene& rs, const core::RenderParams& p) {
    rt::FrameStats off, on;
    const rt::Image a = render(rs, p, core::k_cull_none, &off), b = render(rs, p, core::k_cull_slabs, &on);
    ASSERT_EQ(a.rgb.size(), b.rgb.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < a.rgb.size(); ++i) differ += a.rgb[i] != b.rgb[i];
    EXPECT_EQ(differ, 0u) << "leaf culling changed the image";
    EXPECT_EQ(off.rays(), on.rays());
    EXPECT_EQ(off.culled, 0u);
    EXPECT_GT(on.culled, 0u);
    EXPECT_LT(on.splat_tests, off.splat_tests);
}

TEST(LeafBounds, ImagesAreIdenticalWithAndWithoutThem) {
    // A mirror room (reflections leave walls at every bounce) with a glass ball (refracted rays
    // travel inside: back faces) and shadows from two lights.
    std::vector<TestPoint> pts = room_points(-1.0, 1.0, 70, -1, {200, 180, 160, 255});
    const auto ball = sphere_points({0.2, -0.4, -0.3}, 0.35, 12000, false, {90, 140, 250, 255});
    pts.insert(pts.end(), ball.begin(), ball.end());
    scene::Scene sc;
    sc.materials.push_back(scene::Material{});
    sc.materials[0].reflectivity = 0.5f;
    sc.materials[0].transmissivity = 0.3f;
    sc.materials[0].refractive_index = 1.4f;
    sc.camera.position = {0.1, 0.2, 0.9};
    sc.camera.look_at = {0, -0.3, -1};
    sc.camera.width = 48;
    sc.camera.height = 40;
    for (const scene::Vec3 l : {scene::Vec3{0.3, 0.8, 0.2}, scene::Vec3{-0.6, 0.2, 0.5}}) {
        scene::PointLight light;
        light.position = l;
        sc.point_lights.push_back(light);
    }
    rt::RenderScene rs = rt::RenderScene::from_pools(sc, {make_pool(make_model(pts, {0, 0, 0}, 24))});
    core::RenderParams p = rs.params();
    p.max_bounces = 5;
    p.shadows = 1;
    expect_same_images(rs, p);
    p.deep_blending = 1;  // the blending window reaches into later leaves
    p.blend_window = 2.0f;
    expect_same_images(rs, p);
}

TEST(LeafBounds, ImagesAreIdenticalForASmallModelFarAway) {
    // thesis 3.6 at extreme scale: a 1e-3 ball 1e4 units from the origin, seen from afar.
    const auto pts = sphere_points({1e4, -2e4, 5e3}, 1e-3, 8000);
    scene::Scene sc;
    sc.materials.push_back(scene::Material{});
    sc.materials[0].reflectivity = 0.4f;
    sc.camera.position = {1e4 + 1e-3, -2e4 + 2e-3, 5e3 + 4e-3};
    sc.camera.look_at = {1e4, -2e4, 5e3};
    sc.camera.width = 32;
    sc.camera.height = 32;
    scene::PointLight light;
    light.position = {1e4 + 3e-3, -2e4 + 5e-3, 5e3 + 1e-3};
    sc.point_lights.push_back(light);
    rt::RenderScene rs = rt::RenderScene::from_pools(sc, {make_pool(make_model(pts, {1e4, -2e4, 5e3}))});
    core::RenderParams p = rs.params();
    p.shadows = 1;
    p.max_bounces = 3;
    expect_same_images(rs, p);
}

}  // namespace
}  // namespace prt::test
