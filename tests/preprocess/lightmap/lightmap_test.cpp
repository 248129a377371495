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
#include "runtime/surface_fixtures.h"
#include "runtime/tool_run.h"

using namespace prt;

namespace {

/// Samples of the scene's first model at one level above its reference level (gi_frame.h: its
/// splat octree's depth, else one from its points or patches), settled on the surface it is traced
/// as, traced, and their light-map octree.
struct Baked {
    std::vector<lightmap::Sample> samples;
    std::size_t dropped = 0;
    gi::GiFrame frame;
    gi::GiOctree tree;
};

Baked bake(const rt::RenderScene& rs, const pool::PoolFile& pool, std::uint32_t per_leaf,
           const lightmap::TraceParams& tp) {
    Baked b;
    const gi::SurfacePoints points = gi::surface_points(pool);
    b.frame = gi::gi_frame(pool, &points);
    lightmap::GatherOptions g;
    g.depth = b.frame.depth > 1 ? b.frame.depth - 1 : 0;
    const float reach = lightmap::settle_reach(rs.view().models[0].surface, points,
                                               b.frame.root_size / static_cast<double>(1ull << g.depth));
    b.samples = lightmap::select_samples(points, 0, rs.view().models[0], b.frame.root_min, b.frame.root_size,
                                         g.depth, per_leaf, reach);
    lightmap::trace_samples(rs.view(), tp, b.samples, 0, 0);
    b.dropped = lightmap::drop_unsettled(b.samples);
    b.tree = lightmap::build_light_map_octree(b.samples, b.frame.root_min, b.frame.root_size, g);
    return b;
}

/// Mean and relative spread of the light map looked up at points of the unit sphere that are not
/// sample points (inward normals), and how many lookups found nothing.
struct Lookups {
    double mean = 0, relative_sd = 0;
    int missing = 0;
};
Lookups look_up_unit_sphere(const gi::GiOctree& tree) {
    const core::LightMapView v{gi::view_of(tree)};
    double sum = 0, sum2 = 0;
    int n = 0;
    Lookups out;
    for (const test::TestPoint& q : test::sphere_points({0, 0, 0}, 1.0, 997, true)) {
        const core::Vec3 pos{float(q.position[0]), float(q.position[1]), float(q.position[2])};
        const core::Vec3 nrm{float(q.normal[0]), float(q.normal[1]), float(q.normal[2])};
        core::Vec3 e;
        if (!core::light_map_irradiance(v, pos, nrm, e)) {
            ++out.missing;
            continue;
        }
        sum += e.y;
        sum2 += double(e.y) * e.y;
        ++n;
    }
    if (n > 0) {
        out.mean = sum / n;
        out.relative_sd = std::sqrt(std::max(0.0, sum2 / n - out.mean * out.mean)) / out.mean;
    }
    return out;
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
        test::white_room(R"([{"type": "point", "position": [0, 0, 0], "color": [1, 1, 1]}])", pool);
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
    const rt::RenderScene lit = test::white_room(
        R"([{"type": "area", "corner": [-0.01, 0, -0.01], "edge_u": [0.02, 0, 0], "edge_v": [0, 0, 0.02],
             "samples": 1}])",
        pool);
    const Baked baked = bake(lit, *pool, 1, tp);
    ASSERT_GT(baked.samples.size(), 100u);
    const double expected = a + a * a + a * a * a;
    double mean = 0;
    for (const lightmap::Sample& s : baked.samples) mean += s.irradiance[1] / baked.samples.size();
    EXPECT_NEAR(mean, expected, 0.02 * expected);
    const Baked dark = bake(test::white_room("[]", pool), *pool, 1, tp);
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

TEST(LightMap, TheClosedWhiteRoomIsUniformOnEverySurface) {
    // Issue 20: the closed white room of the first test traced as ISO, MLS and Bezier patches. The
    // ISO and MLS rooms are built by the tools from a pool of points only (no splat octree: the
    // frame comes from the points), and their samples are settled onto the traced surface first;
    // the patch room (8 patches within 5e-4 of the sphere, normals inward) samples the patches.
    // Every wall is still lit at normal incidence, so the light map is a + a^2 + a^3 everywhere.
    PRT_SKIP_WITHOUT_SURFACE_TOOLS();
    const test::TempDir dir("prt_lightmap_surfaces");
    const double a = 0.5, expected = a + a * a + a * a * a;
    test::write_points_pool(test::make_model(test::sphere_points({0, 0, 0}, 1.0, 40000, true), {0, 0, 0}),
                            dir.path / "points.pool");
    test::must_run("prt-iso",
                   (dir.path / "points.pool").string() + " -o " + (dir.path / "iso.pool").string() + " -q",
                   dir.path);
    test::must_run("prt-mls",
                   (dir.path / "points.pool").string() + " -o " + (dir.path / "mls.pool").string() + " -q",
                   dir.path);
    const double origin[3] = {0, 0, 0};
    test::sphere_patch_file(dir.path, 1.0, origin, true);
    test::must_run("prt-patches",
                   (dir.path / "sphere.bpt").string() + " -o " + (dir.path / "patches.pool").string() +
                       " --orient none -q",
                   dir.path);
    lightmap::TraceParams tp;
    tp.rays = 8;
    tp.bounces = 3;
    for (const char* surface : {"iso", "mls", "patches"}) {
        SCOPED_TRACE(surface);
        const auto pool = std::make_shared<const pool::PoolFile>(
            pool::PoolFile::open(dir.path / (std::string(surface) + ".pool")));
        const rt::RenderScene rs = test::white_room(
            R"([{"type": "point", "position": [0, 0, 0], "color": [1, 1, 1]}])", pool, surface);
        const Baked baked = bake(rs, *pool, 2, tp);
        EXPECT_EQ(baked.frame.from, std::string(surface) == "patches" ? "the patches" : "the points");
        ASSERT_GT(baked.samples.size(), 200u);
        EXPECT_LT(baked.dropped, baked.samples.size() / 100) << "samples the probe did not settle";
        double mean = 0;
        for (const lightmap::Sample& s : baked.samples) {
            mean += s.irradiance[1] / baked.samples.size();
            // Settled onto the traced surface: on the sphere (ISO, MLS and patches all lie within
            // a small fraction of a point spacing of it).
            const double r =
                std::sqrt(double(s.position[0]) * s.position[0] + double(s.position[1]) * s.position[1] +
                          double(s.position[2]) * s.position[2]);
            ASSERT_NEAR(r, 1.0, 0.01);
        }
        EXPECT_NEAR(mean, expected, 0.03 * expected);
        const Lookups l = look_up_unit_sphere(baked.tree);
        EXPECT_EQ(l.missing, 0);
        EXPECT_NEAR(l.mean, expected, 0.04 * expected);
        EXPECT_LT(l.relative_sd, 0.04);
    }
}

TEST(LightMapTool, BakesModelsWithoutASplatOctreeAndNamesAModelWithNothingToBakeOn) {
    // Issue 20: prt-lightmap on an ISO room with no splat octree (frame from its points); a model
    // whose pool has neither points nor patches (bricks alone) fails in one line naming the model.
    PRT_SKIP_WITHOUT_SURFACE_TOOLS();
    const test::TempDir dir("prt_lightmap_iso_tool");
    test::write_points_pool(test::make_model(test::sphere_points({0, 0, 0}, 1.0, 8000, true), {0, 0, 0}),
                            dir.path / "room.pool");
    test::must_run("prt-iso",
                   (dir.path / "room.pool").string() + " -o " + (dir.path / "room.pool").string() + " -q",
                   dir.path);
    std::ofstream(dir.path / "scene.json") << R"({"lights": [{"type": "point", "position": [0, 0, 0]}],
        "models": [{"name": "room", "pool": "room.pool", "surface": "iso"}]})";
    test::ToolRun r =
        test::run_tool("prt-lightmap", (dir.path / "scene.json").string() + " --rays 4", dir.path);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("frame of the points"), std::string::npos) << r.err;
    const pool::PoolFile p = pool::PoolFile::open(dir.path / "room.pool");
    EXPECT_GT(rt::load_light_map_view(p).tree.leaf_count, 0u);
    EXPECT_FALSE(p.has(pool::SectionType::octree_info));
    // A bricked pool without its points (prt-bricks' default): the bricks give the frame, but there
    // is nothing to draw light-map samples from.
    test::write_model_pool(test::make_model(test::sphere_points({0, 0, 0}, 1.0, 8000, true), {0, 0, 0}),
                           dir.path / "splats.pool");
    test::must_run("prt-bricks",
                   (dir.path / "splats.pool").string() + " -o " + (dir.path / "bare.pool").string() + " -q",
                   dir.path);
    std::ofstream(dir.path / "bare.json") << R"({"lights": [{"type": "point", "position": [0, 0, 0]}],
        "models": [{"name": "shell", "pool": "bare.pool"}]})";
    r = test::run_tool("prt-lightmap", (dir.path / "bare.json").string() + " --rays 4 --quiet", dir.path);
    EXPECT_EQ(r.code, 1);
    test::expect_one_line(r.err, {"bare.json", "model 'shell'", "no points and no patches"});
}

TEST(LightMapTool, APoolPlacedTwiceGetsALightMapPerPlacement) {
    // Issue 20: a white floor placed twice, once beside a red wall and once alone far away, each
    // under its own light. The indirect light differs: the first placement's map holds the wall's
    // red, the second's nothing (its paths see only the black environment). One pool, two maps,
    // each found by its placement's key; the renderer gives each model its own.
    const auto dir = test::fresh_dir("lightmap_placements");
    test::write_model_pool(
        test::make_model(test::rect_points({0, 0, -1}, {2, 0, 0}, {0, 0, 2}, {0, 1, 0}, 100), {0, 0, 0}),
        dir / "floor.pool");
    test::write_model_pool(
        test::make_model(
            test::rect_points({0, 0, -1}, {0, 2, 0}, {0, 0, 2}, {1, 0, 0}, 100, {255, 0, 0, 255}), {0, 0, 0}),
        dir / "wall.pool");
    std::ofstream(dir / "scene.json") << R"({
        "lights": [{"type": "point", "position": [1, 1.5, 0]}, {"type": "point", "position": [11, 1.5, 0]}],
        "materials": [{"name": "m", "diffuse": [0.9, 0.9, 0.9], "diffuse_reflectance": 1}],
        "models": [{"name": "floor by the wall", "pool": "floor.pool"},
                   {"name": "wall", "pool": "wall.pool"},
                   {"name": "floor alone", "pool": "floor.pool", "transform": {"translate": [10, 0, 0]}}],
        "environment": {"color": [0, 0, 0]},
        "render": {"light_map": true}})";
    const test::ToolRun r =
        test::run_tool("prt-lightmap", (dir / "scene.json").string() + " --rays 32 --bounces 1", dir);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("one light map per placement"), std::string::npos) << r.err;
    const scene::Scene sc = scene::load_scene(dir / "scene.json");
    const std::uint32_t by_wall = pool::placement_key(sc.models[0].transform);
    const std::uint32_t alone = pool::placement_key(sc.models[2].transform);
    {
        const pool::PoolFile floor = pool::PoolFile::open(dir / "floor.pool");
        const std::vector<pool::GiSections> maps = pool::validate_light_maps(floor);
        ASSERT_EQ(maps.size(), 2u);
        EXPECT_EQ(maps[0].info.placement, by_wall);
        EXPECT_EQ(maps[1].info.placement, alone);
        EXPECT_GT(maps[0].info.total[0], 0.0f);
        EXPECT_LT(maps[1].info.total[0], 0.01f * maps[0].info.total[0])
            << "the lone floor sees nothing to bounce";
        EXPECT_EQ(rt::load_light_map_view(floor, alone).tree.nodes, maps[1].nodes.data());
        EXPECT_EQ(rt::load_light_map_view(floor, 12345).tree.nodes, nullptr) << "no map for that placement";
        // The wall, placed once, has one map for any placement.
        const std::vector<pool::GiSections> wall =
            pool::validate_light_maps(pool::PoolFile::open(dir / "wall.pool"));
        ASSERT_EQ(wall.size(), 1u);
        EXPECT_EQ(wall[0].info.placement, 0u);
    }
    const rt::RenderScene rs = rt::RenderScene::load(sc);
    const core::SceneView v = rs.view();
    core::Vec3 near_wall, lone;
    ASSERT_TRUE(core::light_map_irradiance(v.models[0].light_map, core::Vec3{0.1f, 0, 0}, core::Vec3{0, 1, 0},
                                           near_wall));
    EXPECT_GT(near_wall.x, 0.02f);
    EXPECT_LT(near_wall.y, 0.1f * near_wall.x) << "the red wall reflects no green";
    if (core::light_map_irradiance(v.models[2].light_map, core::Vec3{0.1f, 0, 0}, core::Vec3{0, 1, 0},
                                   lone)) {
        EXPECT_LT(lone.x, 0.01f * near_wall.x) << "the lone floor took the other placement's map";
    }
}
