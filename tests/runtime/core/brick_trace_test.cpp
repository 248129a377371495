// Tracing bricked pools (issue 17, runtime/core bricks.h): a bricked pool's image equals the float
// octree's within the codec's error (hit/miss flips only at silhouettes), whatever the brick cut;
// bricks that are not resident fall back to their LOD discs, counted and requested; a ray crossing
// many bricks finds the nearest surface (analytic planes); RenderScene loads bricked pools.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <vector>

#include "bricks_test_data.h"
#include "prt/core/bricks.h"
#include "prt/cpu/cpu_backend.h"
#include "prt/formats/brick_sections.h"
#include "prt/runtime/leaf_bounds.h"
#include "prt/runtime/render_scene.h"

namespace {

using namespace prt;
using core::Vec3;
using pool::PoolFile;

constexpr double k_pi = 3.14159265358979323846;
constexpr double k_sphere_radius = 2.0;
const double k_centre[3] = {10.0, -3.0, 1.0};

/// A sphere of n points with radii covering it (about 2 spacings), colours from the position.
std::vector<std::byte> sphere_pool(std::size_t n) {
    const test::SplatSet s = test::sphere_points(n, 11, k_sphere_radius, k_centre);
    pre::PointCloud cloud;
    const double spacing = std::sqrt(4 * k_pi * k_sphere_radius * k_sphere_radius / double(n));
    for (std::size_t i = 0; i < s.positions.size(); ++i) {
        const pool::Float3& p = s.positions[i];
        cloud.positions.push_back({p.x, p.y, p.z});
        const double u = (p.x - k_centre[0]) / k_sphere_radius, v = (p.y - k_centre[1]) / k_sphere_radius,
                     w = (p.z - k_centre[2]) / k_sphere_radius;
        cloud.colors.push_back(
            {std::uint8_t(127 + 120 * u), std::uint8_t(127 + 120 * v), std::uint8_t(127 + 120 * w), 255});
        cloud.radii.push_back(float(spacing * (1.8 + 0.4 * double(i % 3))));
    }
    cloud.normals = s.normals;
    return test::octree_pool_bytes(cloud, 16);
}

/// Both views of a pool holding the float octree and bricks.
struct Views {
    std::unique_ptr<PoolFile> pool;
    core::OctreeView octree;
    std::vector<core::LeafBounds> bounds;
    const pool::Rgba8* colors = nullptr;
    core::BrickView bricks;
    std::vector<core::BrickLeafBounds> brick_bounds;
    std::vector<std::uint32_t> brick_first;
    pool::BrickSections sections;
    Vec3 centre;  ///< the sphere's centre, local frame
    float max_radius = 0;
};

std::unique_ptr<Views> make_views(std::vector<std::byte> bytes) {
    auto v = std::make_unique<Views>();
    v->pool = std::make_unique<PoolFile>(PoolFile::from_bytes(std::move(bytes), "bricked"));
    const pool::SplatOctreeSections f = pool::splat_octree(*v->pool, "test");
    v->octree = core::make_octree_view(f.info, f.nodes.data(), f.leaf_info.data(), f.splats.data());
    v->bounds = rt::build_leaf_bounds(v->octree, 1);
    v->octree.leaf_bounds = v->bounds.data();
    v->colors = v->pool->array<pool::Rgba8>(pool::SectionType::colors).data();
    v->sections = pool::validate_bricks(*v->pool);
    const pool::BrickSections& s = v->sections;
    v->bricks = core::make_brick_view(
        s.info, s.top_nodes.data(), s.table.data(), reinterpret_cast<const unsigned char*>(s.data.data()),
        s.data.size(), s.lod.data(), s.lod_table.empty() ? nullptr : s.lod_table.data(),
        s.lod_table.empty() ? nullptr : s.lod_nodes.data(),
        s.lod_table.empty() ? nullptr : s.lod_discs.data(), std::uint32_t(s.lod_nodes.size()));
    v->brick_bounds = rt::build_brick_leaf_bounds(v->bricks, v->brick_first, 2);
    v->bricks.leaf_bounds = v->brick_bounds.data();
    v->bricks.leaf_bounds_first = v->brick_first.data();
    const pool::ModelInfo& mi = v->pool->model_info();
    v->centre = Vec3{float(k_centre[0] - mi.origin[0]), float(k_centre[1] - mi.origin[1]),
                     float(k_centre[2] - mi.origin[2])};
    for (const pool::Splat& sp : f.splats) v->max_radius = std::max(v->max_radius, sp.radius);
    return v;
}

/// Parallel rays of a size x size grid over a square of half-width 1.25 sphere radii, slightly
/// oblique (no axis-aligned rays), from 8 units in front of the sphere's centre.
struct Grid {
    Vec3 d, u, w;
    std::uint32_t size;
    float half = float(1.25 * k_sphere_radius);
    Grid(std::uint32_t n) : size(n) {
        d = core::normalize(Vec3{0.13f, 0.21f, -1.0f});
        u = core::normalize(core::cross(d, Vec3{0, 1, 0}));
        w = core::cross(u, d);
    }
    /// Ray origin of pixel i and its distance from the sphere's axis (rho: the silhouette is rho = R).
    Vec3 origin(const Views& v, std::uint32_t i, float& rho) const {
        const float x = (2.0f * ((i % size) + 0.5f) / size - 1.0f) * half;
        const float y = (2.0f * ((i / size) + 0.5f) / size - 1.0f) * half;
        rho = std::sqrt(x * x + y * y);
        return v.centre - d * 8.0f + u * x + w * y;
    }
};

struct Pixel {
    bool hit = false;
    core::SplatSample s{};
};

constexpr core::BlendOptions k_blend{1.0f, true};  // the renderer's defaults (deep blending on)

std::vector<Pixel> render_float(const Views& v, const Grid& g) {
    std::vector<Pixel> out(g.size * g.size);
    for (std::uint32_t i = 0; i < out.size(); ++i) {
        float rho;
        core::WalkStats st;
        out[i].hit = core::closest_hit_splats(v.octree, v.colors, g.origin(v, i, rho), g.d, false,
                                              core::k_inf, k_blend, 1u << 16, out[i].s, st);
    }
    return out;
}

std::vector<Pixel> render_bricks(const core::BrickView& b, const Views& v, const Grid& g,
                                 core::WalkStats& stats, std::uint32_t culling = core::k_cull_slabs,
                                 core::LodCone cone = {}) {
    std::vector<Pixel> out(g.size * g.size);
    for (std::uint32_t i = 0; i < out.size(); ++i) {
        float rho;
        out[i].hit = core::closest_hit_bricks(b, g.origin(v, i, rho), g.d, false, core::k_inf, k_blend,
                                              1u << 16, out[i].s, stats, culling, cone);
    }
    return out;
}

/// The bricked image against the float one: hit/miss flips only within a splat radius of the
/// silhouette; away from it (rays meeting the sphere at less than 60 deg from its normal) depth,
/// normal and colour within the codec's error as blending spreads it (bounds below).
void expect_same_image(const Views& v, const Grid& g, const std::vector<Pixel>& a,
                       const std::vector<Pixel>& b) {
    std::size_t flips = 0, compared = 0;
    double max_dt = 0, max_dn = 0, max_dc = 0;
    for (std::uint32_t i = 0; i < a.size(); ++i) {
        float rho;
        g.origin(v, i, rho);
        if (a[i].hit != b[i].hit) {
            ++flips;
            EXPECT_LT(std::fabs(rho - k_sphere_radius), 2.0 * v.max_radius)
                << "flip away from the silhouette, pixel " << i;
            continue;
        }
        if (!a[i].hit || rho > 0.866 * k_sphere_radius) continue;
        ++compared;
        max_dt = std::max(max_dt, double(std::fabs(a[i].s.t - b[i].s.t)));
        const double c = std::clamp(double(core::dot(a[i].s.normal, b[i].s.normal)), -1.0, 1.0);
        max_dn = std::max(max_dn, std::acos(c) * 180.0 / k_pi);
        for (int k = 0; k < 3; ++k)
            max_dc = std::max(max_dc, double(std::fabs(core::component(a[i].s.color, k) -
                                                       core::component(b[i].s.color, k))));
    }
    // Codec (formats/POOL.md): positions within a quantum of a brick's cube, normals within 0.24 deg,
    // radii up to 0.54 % larger, colours within 4/255. A blended sample moves by those errors and by
    // the blending weights 1 - x/R they shift (x by a quantum, R by 0.54 %): a few thousandths of
    // a splat radius in depth for the sphere's curvature, and the normal by the weight shift times
    // the spread of the normals blended (splat radius / sphere radius, about 3 deg here); colours
    // (linear in the position, 120/255 per sphere radius) the same way.
    const double dt_bound = 0.02 * v.max_radius;
    const double dn_bound = 0.24 + 0.02 * (v.max_radius / k_sphere_radius) * 180.0 / k_pi;
    const double dc_bound = 4.0 / 255.0 + 0.02 * (v.max_radius / k_sphere_radius) * 120.0 / 255.0;
    EXPECT_GT(compared, a.size() / 4);
    EXPECT_LT(flips, a.size() / 100) << "hit/miss flips";
    EXPECT_LE(max_dt, dt_bound) << "depth";
    EXPECT_LE(max_dn, dn_bound) << "normal (deg)";
    EXPECT_LE(max_dc, dc_bound) << "colour";
    std::printf(
        "  %zu compared, %zu flips, max depth %.3g (bound %.3g), normal %.3g deg (bound %.3g), colour %.3g\n",
        compared, flips, max_dt, dt_bound, max_dn, dn_bound, max_dc);
}

class BrickTrace : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        s_octree = new PoolFile(PoolFile::from_bytes(sphere_pool(12000), "octree"));
        s_views = make_views(test::bricked_bytes(*s_octree, 1500)).release();
    }
    static void TearDownTestSuite() {
        delete s_views;
        delete s_octree;
    }
    static PoolFile* s_octree;
    static Views* s_views;  ///< N = 1500: a few dozen bricks
};
PoolFile* BrickTrace::s_octree = nullptr;
Views* BrickTrace::s_views = nullptr;

TEST_F(BrickTrace, ImageEqualsTheFloatOctreesWithinTheCodecError) {
    const Grid g(128);
    const std::vector<Pixel> ref = render_float(*s_views, g);
    const auto one = make_views(test::bricked_bytes(*s_octree, 1));          // every filled leaf a brick
    const auto huge = make_views(test::bricked_bytes(*s_octree, 1u << 30));  // one brick, the whole tree
    for (const Views* v : {s_views, one.get(), huge.get()}) {
        SCOPED_TRACE(::testing::Message() << v->bricks.brick_count << " bricks");
        ASSERT_GT(v->bricks.brick_count, 0u);
        core::WalkStats st;
        const std::vector<Pixel> img = render_bricks(v->bricks, *v, g, st);
        EXPECT_EQ(st.fallbacks, 0u) << "every brick is resident";
        EXPECT_EQ(st.truncated, 0u);
        expect_same_image(*v, g, ref, img);
        // Leaf bounds pass leaves unread without changing the image.
        core::WalkStats all_st;
        const std::vector<Pixel> unculled = render_bricks(v->bricks, *v, g, all_st, core::k_cull_none);
        EXPECT_GT(st.culled, 0u);
        EXPECT_LT(st.splat_tests, all_st.splat_tests);
        for (std::uint32_t i = 0; i < img.size(); ++i) {
            ASSERT_EQ(img[i].hit, unculled[i].hit) << i;
            if (img[i].hit) {
                EXPECT_EQ(img[i].s.t, unculled[i].s.t) << i;
            }
        }
    }
    EXPECT_EQ(huge->bricks.brick_count, 1u);
    EXPECT_GT(one->bricks.brick_count, 10 * s_views->bricks.brick_count);
    EXPECT_GT(s_views->bricks.brick_count, 8u);
}

TEST_F(BrickTrace, DirectAndReferencedBricksTraceTheSameImage) {
    // Direct bricks (splats in leaf order, no references) decode the same splats in the same order
    // as referenced ones, so the image is the same bit for bit, with the same work.
    using D = pre::BrickParams::Direct;
    const Grid g(128);
    const auto never = make_views(test::bricked_bytes(*s_octree, 1500, nullptr, true, 32, D::never));
    const auto always = make_views(test::bricked_bytes(*s_octree, 1500, nullptr, true, 32, D::always));
    ASSERT_EQ(never->bricks.brick_count, always->bricks.brick_count);
    core::WalkStats sn, sa;
    const std::vector<Pixel> a = render_bricks(never->bricks, *never, g, sn);
    const std::vector<Pixel> b = render_bricks(always->bricks, *always, g, sa);
    std::size_t hits = 0;
    for (std::uint32_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a[i].hit, b[i].hit) << i;
        if (!a[i].hit) continue;
        ++hits;
        EXPECT_EQ(a[i].s.t, b[i].s.t) << i;
        for (int k = 0; k < 3; ++k) {
            EXPECT_EQ(core::component(a[i].s.normal, k), core::component(b[i].s.normal, k)) << i;
            EXPECT_EQ(core::component(a[i].s.color, k), core::component(b[i].s.color, k)) << i;
        }
    }
    EXPECT_GT(hits, a.size() / 4);
    if (PRT_COUNT_WORK) {
        EXPECT_EQ(sn.splat_tests, sa.splat_tests);
        EXPECT_EQ(sn.leaves, sa.leaves);
    }
}

TEST_F(BrickTrace, TheTracersDecodeIsTheCodecs) {
    // BrickSplats::load decodes as pool::decode_splat does, bit for bit, but for the normal, which it
    // leaves on the octahedron scaled by k_oct_half (the plane test needs no unit normal); unit()
    // gives the codec's unit normal, bit for bit, and the loaded one points the same way.
    const Views& v = *s_views;
    std::size_t checked = 0;
    for (std::uint32_t b = 0; b < v.bricks.brick_count; ++b) {
        core::BrickSplats src;
        core::OctreeView brick;
        ASSERT_TRUE(core::open_brick(v.bricks, b, src, brick));
        const pool::BrickView pv = pool::brick_view(v.sections.payload(b));
        for (std::uint32_t i = 0; i < brick.splat_count; ++i) {
            const pool::Splat s = src.load(i);
            const pool::DecodedSplat d = pool::decode_splat(pv.splats[pv.ref(i)], *pv.header);
            ASSERT_EQ(s.position.x, d.position.x);
            ASSERT_EQ(s.position.y, d.position.y);
            ASSERT_EQ(s.position.z, d.position.z);
            ASSERT_EQ(s.radius, d.radius);
            const Vec3 u = src.unit(Vec3{s.normal.x, s.normal.y, s.normal.z});
            ASSERT_EQ(u.x, d.normal.x) << "brick " << b << " splat " << i;
            ASSERT_EQ(u.y, d.normal.y);
            ASSERT_EQ(u.z, d.normal.z);
            // on the scaled octahedron, in exact integers
            ASSERT_EQ(std::fabs(s.normal.x) + std::fabs(s.normal.y) + std::fabs(s.normal.z),
                      pool::k_oct_half);
            ASSERT_EQ(s.normal.x, std::round(s.normal.x));
            ASSERT_EQ(s.normal.y, std::round(s.normal.y));
            ++checked;
        }
    }
    EXPECT_EQ(checked, v.sections.info.splat_count);
}

TEST_F(BrickTrace, OneWalkVisitsTheFloatOctreesLeaves) {
    // Bricks are subtrees of the same octree and the walk crosses from brick to brick in one walk
    // state (descend_bricked): a ray that meets nothing visits exactly the leaves the float walk
    // visits, however the tree is cut into bricks (brick borders add no steps).
    if (!PRT_COUNT_WORK) GTEST_SKIP() << "work counters compiled out (PRT_COUNT_WORK=0)";
    const Grid g(96);
    const auto one = make_views(test::bricked_bytes(*s_octree, 1));
    std::size_t misses = 0;
    for (const Views* v : {s_views, one.get()}) {
        for (std::uint32_t i = 0; i < g.size * g.size; ++i) {
            float rho;
            const core::Vec3 o = g.origin(*v, i, rho);
            core::WalkStats fs, bs;
            core::SplatSample a, b;
            const bool fh = core::closest_hit_splats(v->octree, v->colors, o, g.d, false, core::k_inf,
                                                     k_blend, 1u << 16, a, fs, core::k_cull_none);
            const bool bh = core::closest_hit_bricks(v->bricks, o, g.d, false, core::k_inf, k_blend, 1u << 16,
                                                     b, bs, core::k_cull_none);
            if (fh || bh) continue;
            ++misses;
            ASSERT_EQ(bs.leaves, fs.leaves) << "ray " << i << ", " << v->bricks.brick_count << " bricks";
        }
    }
    EXPECT_GT(misses, std::size_t(g.size) * g.size / 4);
}

TEST_F(BrickTrace, NonResidentBricksFallBackToTheirLodDiscsAndAreRequested) {
    // Without LOD prefixes (a pool of prt-bricks --lod-splats 0): a missing brick is met as its
    // top-node disc.
    Views& v = *s_views;
    const core::BrickView with_prefixes = v.bricks;
    v.bricks.lod_table = nullptr;
    v.bricks.lod_nodes = nullptr;
    v.bricks.lod_discs = nullptr;
    v.bricks.lod_node_count = 0;
    struct Restore {
        Views& v;
        core::BrickView b;
        ~Restore() { v.bricks = b; }
    } restore{v, with_prefixes};
    const Grid g(64);
    core::WalkStats all_st;
    const std::vector<Pixel> all = render_bricks(v.bricks, v, g, all_st);
    ASSERT_EQ(all_st.fallbacks, 0u);
    // Every other brick resident.
    const std::uint32_t n = v.bricks.brick_count;
    std::vector<const unsigned char*> resident(n, nullptr);
    for (std::uint32_t b = 0; b < n; b += 2) resident[b] = v.bricks.data + v.bricks.table[b].offset;
    std::vector<std::uint32_t> requests(n, 0), any_request(n, 0);
    core::BrickView half = v.bricks;
    half.resident = resident.data();
    half.requests = requests.data();
    std::size_t untouched = 0, touched = 0, lod_hits = 0;
    std::uint64_t fallbacks = 0;
    for (std::uint32_t i = 0; i < g.size * g.size; ++i) {
        std::fill(requests.begin(), requests.end(), 0u);
        float rho;
        const Vec3 o = g.origin(v, i, rho);
        core::WalkStats st;
        core::SplatSample s{};
        const bool hit = core::closest_hit_bricks(half, o, g.d, false, core::k_inf, k_blend, 1u << 16, s, st);
        const auto flagged = std::count(requests.begin(), requests.end(), 1u);
        for (std::uint32_t b = 0; b < n; ++b) {
            if (requests[b]) {
                EXPECT_EQ(b % 2, 1u) << "a resident brick was requested";
            }
            any_request[b] |= requests[b];
        }
        // Streaming asks for the first missing brick on a ray's way only (bricks.h stopped_at_disc).
        EXPECT_EQ(flagged, st.fallbacks > 0 ? 1 : 0) << "one request per ray that fell back, pixel " << i;
        fallbacks += st.fallbacks;
        if (st.fallbacks == 0) {
            // A ray that met only resident bricks sees exactly the all-resident image.
            ++untouched;
            ASSERT_EQ(hit, all[i].hit) << i;
            if (hit) {
                EXPECT_EQ(s.t, all[i].s.t);
                EXPECT_EQ(s.normal.x, all[i].s.normal.x);
            }
        } else if (hit) {
            ++touched;
            // A hit on a LOD disc lies in the plane of one of the discs of the missing bricks.
            const Vec3 p = o + g.d * s.t;
            bool on_disc = false;
            for (std::uint32_t b = 0; b < n; ++b) {
                if (resident[b] != nullptr) continue;
                const pool::LodSplat& l = v.bricks.lod[v.bricks.table[b].top_node];
                const Vec3 c{l.position.x, l.position.y, l.position.z},
                    nn{l.normal.x, l.normal.y, l.normal.z};
                on_disc = on_disc || (std::fabs(core::dot(p - c, nn)) < 1e-3f * l.radius &&
                                      core::length(p - c) <= l.radius * 1.001f);
            }
            lod_hits += on_disc;
        }
    }
    EXPECT_GT(untouched, 100u);
    EXPECT_GT(fallbacks, 0u);
    EXPECT_GT(lod_hits, 0u) << "some rays hit a LOD disc";
    std::printf("  %zu rays untouched, %zu touched and hit (%zu on a LOD disc), %llu fallbacks\n", untouched,
                touched, lod_hits, static_cast<unsigned long long>(fallbacks));
    // Nothing resident: rays still find the sphere's discs, each asking for the first brick it met.
    std::vector<const unsigned char*> none(n, nullptr);
    core::BrickView empty = v.bricks;
    empty.resident = none.data();
    empty.requests = requests.data();
    std::fill(requests.begin(), requests.end(), 0u);
    core::WalkStats st;
    const std::vector<Pixel> lod = render_bricks(empty, v, g, st);
    EXPECT_GT(st.fallbacks, 0u);
    std::size_t hits = 0;
    for (std::uint32_t i = 0; i < lod.size(); ++i) hits += lod[i].hit && all[i].hit;
    EXPECT_GT(hits, 0u);
}

/// Five parallel planes of points, z = 0, 1, ..., 4, normals +z, each in its own bricks.
TEST(BrickTraceOrder, ARayThroughManyBricksFindsTheNearestHit) {
    pre::PointCloud cloud;
    const int side = 60;
    for (int z = 0; z < 5; ++z)
        for (int y = 0; y < side; ++y)
            for (int x = 0; x < side; ++x) {
                cloud.positions.push_back({x * 0.1, y * 0.1, double(z)});
                cloud.normals.push_back({0, 0, 1});
                cloud.radii.push_back(0.1f);
                cloud.colors.push_back({std::uint8_t(50 * z), 0, 0, 255});
            }
    const PoolFile octree = PoolFile::from_bytes(test::octree_pool_bytes(cloud, 8), "planes");
    const auto v = make_views(test::bricked_bytes(octree, 500));
    ASSERT_GT(v->bricks.brick_count, 20u);
    const pool::ModelInfo& mi = v->pool->model_info();
    const Vec3 org{float(-mi.origin[0]), float(-mi.origin[1]), float(-mi.origin[2])};  // world 0 in local
    std::size_t rays = 0;
    for (int k = 0; k < 400; ++k) {
        // Steep rays from above (and rays from below, which see only back faces: misses) landing
        // inside the planes' square, away from its edges.
        const float tx = 1.0f + 4.0f * float(k % 20) / 19.0f, ty = 1.0f + 4.0f * float(k / 20) / 19.0f;
        const Vec3 d = core::normalize(Vec3{0.3f * std::sin(float(k)), 0.3f * std::cos(float(k)), -1.0f});
        const Vec3 target = org + Vec3{tx, ty, 4.0f};
        const Vec3 o = target - d * 20.0f;
        core::WalkStats st;
        core::SplatSample s{};
        ASSERT_TRUE(core::closest_hit_bricks(v->bricks, o, d, false, core::k_inf, k_blend, 1u << 16, s, st))
            << k;
        EXPECT_NEAR(s.t, 20.0f, 1e-3f) << "nearest plane z = 4, ray " << k;
        EXPECT_NEAR(s.color.x, 200.0f / 255.0f, 4.0f / 255.0f) << k;
        EXPECT_NEAR(s.normal.z, 1.0f, 1e-4f);
        // Through the planes from below: only back faces, nothing accepted.
        core::SplatSample b{};
        EXPECT_FALSE(core::closest_hit_bricks(v->bricks, target + d * 20.0f, d * -1.0f, false, core::k_inf,
                                              k_blend, 1u << 16, b, st));
        // Shadow rays agree: blocked from above, along the whole segment.
        EXPECT_TRUE(core::any_hit_bricks(v->bricks, o, d, false, 30.0f, 1u << 16, st));
        EXPECT_FALSE(core::any_hit_bricks(v->bricks, o, d, false, 19.99f, 1u << 16, st));
        EXPECT_EQ(st.fallbacks, 0u);
        ++rays;
    }
    EXPECT_EQ(rays, 400u);
}

/// RenderScene: a pool with bricks only traces them; one with both traces the float octree unless
/// LoadOptions::bricks; the CPU backend's frames agree.
TEST(BrickTraceScene, RenderSceneLoadsBrickedPools) {
    const PoolFile octree = PoolFile::from_bytes(sphere_pool(8000), "octree");
    const auto dir =
        std::filesystem::temp_directory_path() / ("prt_brick_trace_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    auto write = [&](const char* name, const std::vector<std::byte>& bytes) {
        std::ofstream out(dir / name, std::ios::binary);
        out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
        return dir / name;
    };
    const auto both = write("both.pool", test::bricked_bytes(octree, 1000));
    const auto only = write("only.pool", test::bricked_bytes(octree, 1000, nullptr, false));
    auto render = [&](const std::filesystem::path& file, bool bricks, rt::FrameStats& stats, bool& bricked) {
        rt::LoadOptions lo;
        lo.bricks = bricks;
        const rt::RenderScene rs = rt::RenderScene::from_pool(file, lo);
        bricked = rs.models().at(0).view.bricks.top_nodes != nullptr;
        auto backend = cpu::make_cpu_backend(2);
        backend->set_scene(rs.view());
        rt::Image img;
        stats = backend->render(
            rt::FrameRequest{.camera = rs.camera(), .params = rs.params(), .width = 96, .height = 96}, img);
        return img;
    };
    rt::FrameStats fs, bs, os;
    bool f_bricked = true, b_bricked = false, o_bricked = false;
    const rt::Image fi = render(both, false, fs, f_bricked);
    const rt::Image bi = render(both, true, bs, b_bricked);
    const rt::Image oi = render(only, false, os, o_bricked);
    std::filesystem::remove_all(dir);
    EXPECT_FALSE(f_bricked) << "a pool with both traces the float octree by default";
    EXPECT_TRUE(b_bricked);
    EXPECT_TRUE(o_bricked) << "a pool with bricks only traces them";
    EXPECT_EQ(oi.rgba8, bi.rgba8) << "the same bricks, the same image";
    EXPECT_EQ(bs.fallbacks, 0u);
    EXPECT_EQ(fs.primary, bs.primary);
    std::size_t differ = 0, lit = 0;
    for (std::size_t i = 0; i < fi.rgba8.size(); ++i) {
        lit += fi.rgba8[i] != fi.rgba8[0];
        for (int c = 0; c < 3; ++c) {
            const int a = int((fi.rgba8[i] >> (8 * c)) & 255u), b = int((bi.rgba8[i] >> (8 * c)) & 255u);
            differ += std::abs(a - b) > 8;
        }
    }
    EXPECT_GT(lit, fi.rgba8.size() / 10);
    EXPECT_LT(differ, fi.rgba8.size() / 50) << "channels differing by more than 8 of 255";
}

}  // namespace

// ---- Level of detail (LOD prefixes, the footprint stop) ------------------------------------------

TEST(BrickLod, StopLevelIsTheShallowestCellWithinTheFootprint) {
    EXPECT_EQ(core::lod_stop_level(0.0f), core::k_no_lod_stop);
    EXPECT_EQ(core::lod_stop_level(-1.0f), core::k_no_lod_stop);
    EXPECT_EQ(core::lod_stop_level(std::nanf("")), core::k_no_lod_stop);
    EXPECT_EQ(core::lod_stop_level(1.0f), 0u);
    EXPECT_EQ(core::lod_stop_level(1e30f), 0u);
    for (int k = 0; k < 2000; ++k) {  // 2^-l <= f < 2^-(l-1), against ldexp
        const float f = std::ldexp(1.0f + float(k % 97) / 97.0f, -(k % 40));
        const std::uint32_t l = core::lod_stop_level(f);
        if (f >= 1.0f) {
            EXPECT_EQ(l, 0u) << f;
            continue;
        }
        EXPECT_LE(std::ldexp(1.0, -int(l)), double(f)) << f;
        EXPECT_GT(std::ldexp(1.0, -int(l) + 1), double(f)) << f;
    }
}

TEST_F(BrickTrace, LodPrefixesAreTheBricksTopLevelsWithCoveringDiscs) {
    // Checked from each brick's payload alone: the prefix is its nodes of levels 0..D, D the deepest
    // level whose non-empty nodes hold >= 32 references on average (prt-bricks' default M), its
    // words copies of the brick's, and each disc's sphere holds every decoded splat disc below it.
    const pool::BrickSections& s = s_views->sections;
    ASSERT_EQ(s.lod_table.size(), s.table.size());
    std::size_t checked = 0, nodes_total = 0;
    for (std::uint32_t b = 0; b < s.table.size(); ++b) {
        const pool::BrickView bv = pool::brick_view(s.payload(b));
        const pool::BrickLod& l = s.lod_table[b];
        const std::size_t n = bv.nodes.size();
        std::vector<std::uint32_t> level(n, 0), parent(n, 0);
        std::vector<std::uint32_t> nonempty;
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint32_t w = bv.nodes[i];
            if (level[i] >= nonempty.size()) nonempty.resize(level[i] + 1, 0);
            if (pool::node_type(w) != pool::NodeType::empty_leaf) ++nonempty[level[i]];
            if (pool::node_type(w) != pool::NodeType::internal) continue;
            for (std::uint32_t c = 0; c < 8; ++c) {
                level[pool::node_address(w) + c] = level[i] + 1;
                parent[pool::node_address(w) + c] = std::uint32_t(i);
            }
        }
        std::uint32_t deepest = 0;
        while (deepest + 1 < nonempty.size() && nonempty[deepest + 1] * 32ull <= bv.header->splat_count)
            ++deepest;
        std::uint32_t k = 0;
        for (std::size_t i = 0; i < n; ++i) k += level[i] <= deepest;
        ASSERT_EQ(l.node_count, k) << "brick " << b;
        for (std::uint32_t i = 0; i < k; ++i) {
            ASSERT_LE(level[i], deepest) << "the prefix is the top levels, breadth first";
            ASSERT_EQ(s.lod_nodes[l.first + i], bv.nodes[i]);
        }
        nodes_total += k;
        const double quantum = double(bv.header->quant_size) / pool::k_position_max_code * std::sqrt(3.0);
        for (std::size_t i = 0; i < n; ++i) {
            if (pool::node_type(bv.nodes[i]) != pool::NodeType::filled_leaf) continue;
            const std::uint32_t leaf = pool::node_address(bv.nodes[i]);
            for (std::uint32_t r = bv.leaf_info[leaf]; r < bv.leaf_info[leaf + 1]; ++r) {
                const pool::DecodedSplat sp = pool::decode_splat(bv.splats[bv.ref(r)], *bv.header);
                for (std::uint32_t a = std::uint32_t(i);; a = parent[a]) {
                    if (a < k) {
                        const pool::CompressedSplat& c = s.lod_discs[l.first + a];
                        ASSERT_NE(c.nr >> 20, 0u) << "a node with splats below has a disc";
                        const pool::DecodedSplat d = pool::decode_lod_disc(c, l);
                        const double dx = double(sp.position.x) - d.position.x,
                                     dy = double(sp.position.y) - d.position.y,
                                     dz = double(sp.position.z) - d.position.z;
                        EXPECT_LE(std::sqrt(dx * dx + dy * dy + dz * dz) + sp.radius,
                                  d.radius + 2 * quantum + 0.01 * sp.radius)
                            << "brick " << b << " node " << a;
                        ++checked;
                    }
                    if (a == 0) break;
                }
            }
        }
    }
    EXPECT_GT(checked, s.info.splat_count);
    EXPECT_LT(nodes_total, s.info.splat_count / 4) << "the prefixes are a small part of the bricks";
    std::printf("  %zu prefix nodes for %llu references\n", nodes_total,
                static_cast<unsigned long long>(s.info.splat_count));
}

TEST_F(BrickTrace, WhereARayStopsNeverDependsOnWhichBricksAreResident) {
    // For footprints from a quarter of the root cube down to a few leaves: a render with no brick
    // resident equals the in-core render on every ray that needed no brick (no fallback), and at
    // the coarse footprints no ray needs one. The LOD hits lie on the sphere within the flatness of
    // the cells they stopped in. So a streamed view converges to the in-core image.
    const Views& v = *s_views;
    const Grid g(64);
    const std::uint32_t n = v.bricks.brick_count;
    std::vector<const unsigned char*> none(n, nullptr);
    std::vector<std::uint32_t> requests(n, 0);
    core::BrickView empty = v.bricks;
    empty.resident = none.data();
    empty.requests = requests.data();
    core::WalkStats full_st;
    const std::vector<Pixel> full = render_bricks(v.bricks, v, g, full_st);
    std::size_t previous_free = g.size * g.size + 1;
    for (const float fraction : {1.0f / 4, 1.0f / 16, 1.0f / 64, 1.0f / 256}) {
        const float w = v.bricks.root_size * fraction;
        SCOPED_TRACE(::testing::Message() << "footprint " << w);
        const core::LodCone cone{w, 0.0f};
        core::WalkStats in_core_st;
        const std::vector<Pixel> in_core =
            render_bricks(v.bricks, v, g, in_core_st, core::k_cull_slabs, cone);
        EXPECT_EQ(in_core_st.fallbacks, 0u);
        std::size_t free = 0, hits = 0;
        for (std::uint32_t i = 0; i < g.size * g.size; ++i) {
            float rho;
            const Vec3 o = g.origin(v, i, rho);
            core::WalkStats st;
            core::SplatSample s{};
            const bool hit = core::closest_hit_bricks(empty, o, g.d, false, core::k_inf, k_blend, 1u << 16, s,
                                                      st, core::k_cull_slabs, cone);
            if (st.fallbacks != 0) continue;
            ++free;
            ASSERT_EQ(hit, in_core[i].hit) << i;
            if (!hit) continue;
            ++hits;
            ASSERT_EQ(s.t, in_core[i].s.t) << i;
            ASSERT_EQ(s.normal.x, in_core[i].s.normal.x) << i;
            ASSERT_EQ(s.color.y, in_core[i].s.color.y) << i;
            // on the sphere within the sagitta of a cell of the footprint (3 s^2 / 2R) and a splat radius
            const Vec3 p = o + g.d * s.t;
            EXPECT_NEAR(core::length(p - v.centre), k_sphere_radius,
                        1.5 * w * w / k_sphere_radius + 2.0 * v.max_radius + 0.02 * w)
                << i;
        }
        if (fraction >= 1.0f / 4) {
            EXPECT_EQ(free, std::size_t(g.size) * g.size) << "no brick needed";
        }
        if (fraction >= 1.0f / 64) {
            EXPECT_GT(hits, 0u);
            if (PRT_COUNT_WORK) {
                EXPECT_LT(in_core_st.leaves, full_st.leaves) << "coarse stops visit fewer nodes";
            }
        }
        EXPECT_LE(free, previous_free) << "finer footprints need more bricks";
        previous_free = free;
        std::printf("  footprint %.4f: %zu of %u rays need no brick, %zu hits\n", w, free, g.size * g.size,
                    hits);
    }
    EXPECT_LT(previous_free, std::size_t(g.size) * g.size) << "the finest footprint needs bricks";
    (void)full;
}
