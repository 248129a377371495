// Tests of prt-lightmap (thesis 5.3): a uniformly lit closed white room (the inside of a sphere with
// a point light at its centre) has a uniform light map equal to the analytic multi-bounce value;
// color bleeds from a red wall onto a white floor and not across the normal test; the tool writes
// the sections in place.
#include "lightmap.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>

#include "gi_test_util.h"
#include "prt/core/gi.h"
#include "prt/runtime/gi_pool.h"
#include "runtime/tool_run.h"

using namespace prt;

namespace {

/// Samples of the scene's first model at one level above its splat octree, traced, and their
/// light-map octree.
struct Baked {
    std::vector<lightmap::Sample> samples;
    gi::GiOctree tree;
};

Baked bake(const rt::RenderScene& rs, const pool::PoolFile& pool, std::uint32_t per_leaf,
           const lightmap::TraceParams& tp) {
    double root_min[3], root_size;
    std::uint32_t depth;
    gi::splat_root(pool, root_min, root_size, depth);
    lightmap::GatherOptions g;
    g.depth = depth > 1 ? depth - 1 : 0;
    Baked b;
    b.samples = lightmap::select_samples(pool, rs.view().models[0], root_min, root_size, g.depth, per_leaf);
    lightmap::trace_samples(rs.view(), tp, b.samples, 0, 0);
    b.tree = lightmap::build_light_map_octree(b.samples, root_min, root_size, g);
    return b;
}

/// The closed white room of the first tests (a sphere of radius 1, normals inward, albedo 0.5)
/// lit by `lights` (a JSON array).
rt::RenderScene white_room(const std::string& lights, const std::shared_ptr<const pool::PoolFile>& pool) {
    return test::load_gi_scene(R"({"lights": )" + lights + R"(,
        "materials": [{"name": "white", "diffuse": [0.5, 0.5, 0.5], "specular": [0, 0, 0], "diffuse_reflectance": 1,
                       "use_point_colors": false}],
        "models": [{"name": "room", "pool": "room.pool"}],
        "environment": {"color": [0, 0, 0]}})",
                               {pool});
}

}  // namespace

TEST(LightMap, UniformlyLitClosedWhiteRoomIsUniform) {
    // Inside a sphere (normals inward) with a light of color 1 at its centre, every surface point
    // gets direct irradiance 1 (renderer units: no falloff, normal incidence) and sends albedo x
    // its irradiance; every path hits the sphere, so with B vertices per path the indirect
    // irradiance is a + a^2 + ... + a^B everywhere.
    const double a = 0.5;
    const std::uint32_t bounces = 3;
    test::TestModel m = test::make_model(test::sphere_points({0, 0, 0}, 1.0, 40000, true), {0, 0, 0});
    const auto pool = test::make_pool(m);
    const rt::RenderScene rs =
        white_room(R"([{"type": "point", "position": [0, 0, 0], "color": [1, 1, 1]}])", pool);
    lightmap::TraceParams tp;
    tp.rays = 8;
    tp.bounces = bounces;
    const Baked baked = bake(rs, *pool, 2, tp);
    const std::vector<lightmap::Sample>& samples = baked.samples;
    ASSERT_GT(samples.size(), 200u);
    double expected = 0, p = 1;
    for (std::uint32_t b = 0; b < bounces; ++b) expected += (p *= a);
    double mean = 0;
    for (const lightmap::Sample& s : samples) mean += s.irradiance[1] / samples.size();
    EXPECT_NEAR(mean, expected, 0.02 * expected);
    const gi::GiOctree& tree = baked.tree;
    const core::LightMapView v{gi::view_of(tree)};
    // Look up at points of the sphere that are not sample points.
    double sum = 0, sum2 = 0;
    int n = 0, missing = 0;
    for (const test::TestPoint& q : test::sphere_points({0, 0, 0}, 1.0, 997, true)) {
        const core::Vec3 pos{float(q.position[0]), float(q.position[1]), float(q.position[2])};
        const core::Vec3 nrm{float(q.normal[0]), float(q.normal[1]), float(q.normal[2])};
        core::Vec3 e;
        if (!core::light_map_irradiance(v, pos, nrm, e)) {
            ++missing;
            continue;
        }
        sum += e.y;
        sum2 += double(e.y) * e.y;
        ++n;
        // The other side of the wall has no light map.
        core::Vec3 none;
        EXPECT_FALSE(core::light_map_irradiance(v, pos, nrm * -1.0f, none));
    }
    EXPECT_EQ(missing, 0);
    ASSERT_GT(n, 0);
    const double lm_mean = sum / n, sd = std::sqrt(std::max(0.0, sum2 / n - lm_mean * lm_mean));
    EXPECT_NEAR(lm_mean, expected, 0.03 * expected);
    EXPECT_LT(sd / lm_mean, 0.03) << "not uniform: mean " << lm_mean << " sd " << sd;
}

TEST(LightMap, AnAreaLightLightsTheLightMap) {
    // The closed white room of the test above lit by a small area light at its centre instead (issue
    // 20): the renderer's direct light from an area light of color I sampled by area is I cos theta
    // (path.h, no falloff), so every wall gets 1 and the indirect irradiance is a + a^2 + a^3 again;
    // with no light at all it is zero.
    const double a = 0.5;
    test::TestModel m = test::make_model(test::sphere_points({0, 0, 0}, 1.0, 40000, true), {0, 0, 0});
    const auto pool = test::make_pool(m);
    lightmap::TraceParams tp;
    tp.rays = 8;
    tp.bounces = 3;
    const rt::RenderScene lit = white_room(
        R"([{"type": "area", "corner": [-0.01, 0, -0.01], "edge_u": [0.02, 0, 0], "edge_v": [0, 0, 0.02],
             "samples": 1}])",
        pool);
    const Baked baked = bake(lit, *pool, 1, tp);
    ASSERT_GT(baked.samples.size(), 100u);
    const double expected = a + a * a + a * a * a;
    double mean = 0;
    for (const lightmap::Sample& s : baked.samples) mean += s.irradiance[1] / baked.samples.size();
    EXPECT_NEAR(mean, expected, 0.02 * expected);
    const Baked dark = bake(white_room("[]", pool), *pool, 1, tp);
    double dark_max = 0;
    for (const lightmap::Sample& s : dark.samples) dark_max = std::max<double>(dark_max, s.irradiance[1]);
    EXPECT_EQ(dark_max, 0.0);
}

TEST(LightMap, ColorBleedsFromARedWallOntoTheFloor) {
    // A white floor (y = 0) and a red wall (x = 0, facing +x), lit from above: the floor near the
    // wall receives red light; far from it, little. The wall's own map rejects the floor's samples.
    std::vector<test::TestPoint> pts =
        test::rect_points({0, 0, -1}, {2, 0, 0}, {0, 0, 2}, {0, 1, 0}, 140, {255, 255, 255, 255});
    for (const test::TestPoint& p :
         test::rect_points({0, 0, -1}, {0, 2, 0}, {0, 0, 2}, {1, 0, 0}, 140, {255, 0, 0, 255}))
        pts.push_back(p);
    test::TestModel m = test::make_model(pts, {0, 0, 0});
    const auto pool = test::make_pool(m);
    const rt::RenderScene rs = test::load_gi_scene(R"({
        "lights": [{"type": "point", "position": [1, 1.5, 0], "casts_shadows": true}],
        "materials": [{"name": "m", "diffuse": [0.9, 0.9, 0.9], "specular": [0, 0, 0], "diffuse_reflectance": 1}],
        "models": [{"name": "corner", "pool": "c.pool"}],
        "environment": {"color": [0, 0, 0]}})",
                                                   {pool});
    lightmap::TraceParams tp;
    tp.rays = 32;
    tp.bounces = 1;
    const gi::GiOctree tree = bake(rs, *pool, 2, tp).tree;
    const core::LightMapView v{gi::view_of(tree)};
    core::Vec3 near_wall, far_from_wall, on_wall;
    ASSERT_TRUE(core::light_map_irradiance(v, core::Vec3{0.1f, 0.0f, 0.0f}, core::Vec3{0, 1, 0}, near_wall));
    ASSERT_TRUE(
        core::light_map_irradiance(v, core::Vec3{1.8f, 0.0f, 0.0f}, core::Vec3{0, 1, 0}, far_from_wall));
    ASSERT_TRUE(core::light_map_irradiance(v, core::Vec3{0.0f, 0.5f, 0.0f}, core::Vec3{1, 0, 0}, on_wall));
    EXPECT_GT(near_wall.x, 0.02f);
    EXPECT_LT(near_wall.y, 0.1f * near_wall.x) << "the red wall reflects no green";
    EXPECT_GT(near_wall.x, 3.0f * far_from_wall.x);
    // The wall sees the white floor: its indirect light is white (the floor's red-free samples do
    // not leak into it, nor the wall's red into the floor's green).
    EXPECT_GT(on_wall.y, 0.5f * on_wall.x);
}

TEST(LightMapTool, WritesTheLightMapInPlace) {
    const auto dir = test::fresh_dir("lightmap_tool");
    test::write_model_pool(test::make_model(test::sphere_points({0, 0, 0}, 1.0, 8000, true), {0, 0, 0}),
                           dir / "room.pool");
    std::ofstream(dir / "scene.json") << R"({"lights": [{"type": "point", "position": [0, 0, 0]}],
        "models": [{"name": "room", "pool": "room.pool"}]})";
    test::ToolRun r = test::run_tool("prt-lightmap", "--help", dir);
    EXPECT_EQ(r.code, 0);
    for (const char* opt : {"--rays", "--bounces", "--levels-above", "--samples-per-leaf", "--gather-radius",
                            "--normal-reject", "--threads", "--quiet"})
        EXPECT_NE(r.out.find(opt), std::string::npos) << opt;
    r = test::run_tool("prt-lightmap", (dir / "scene.json").string() + " --rays 4 --quiet", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(r.err.empty()) << r.err;
    const pool::PoolFile p = pool::PoolFile::open(dir / "room.pool");
    EXPECT_GT(rt::load_light_map_view(p).tree.leaf_count, 0u);
    EXPECT_NE(p.provenance_json().find("prt-lightmap"), std::string::npos);
    r = test::run_tool("prt-lightmap", (dir / "missing.json").string(), dir);
    EXPECT_EQ(r.code, 1);
    EXPECT_EQ(test::lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("missing.json"), std::string::npos) << r.err;
}
