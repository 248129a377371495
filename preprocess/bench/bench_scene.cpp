#include "bench_scene.h"

#include <algorithm>
#include <cmath>

#include "octree_build.h"
#include "point_cloud.h"
#include "prt/formats/scene.h"
#include "prt/tool.h"
#include "synth.h"

namespace prt::player {

void add_scene_options(CLI::App& app, BenchSceneOptions& o, const char* pool_help, const char* max_leaf_help,
                       bool save_pool) {
    app.add_option("pool", o.pool, pool_help)->check(prt::tool::ExistingInput);
    app.add_option("--scene", o.scene, "Scene JSON (camera, lights, materials)")
        ->check(prt::tool::ExistingInput);
    app.add_option("--synthetic", o.synthetic, "Points of the synthetic room when no pool is given")
        ->check(CLI::Range(std::uint64_t{1000}, std::uint64_t{1} << 31));
    app.add_option("--max-leaf", o.max_leaf, max_leaf_help)->check(CLI::Range(1u, 100000u));
    if (save_pool) app.add_option("--save-pool", o.save_pool, "Also write the synthetic room's pool here");
    app.add_option("--width", o.width, "Image width")->check(CLI::Range(1u, 16384u));
    app.add_option("--height", o.height, "Image height")->check(CLI::Range(1u, 16384u));
}

std::shared_ptr<const pool::PoolFile> synthetic_room_pool(std::uint64_t n, std::uint32_t max_leaf,
                                                          const std::filesystem::path& save, bool quiet) {
    synth::SynthOptions so;
    so.shape.kind = synth::ShapeKind::room;
    so.shape.room = synth::Room::standard(2.0);
    so.count = n;
    so.colors = synth::ColorMode::parts;
    synth::SynthResult sr = synth::synthesize(so);
    // thesis 3.1: radius = distance to the k-th neighbour; for uniform density n/A that distance
    // is about sqrt(k A / (pi n)).
    const double area = synth::surface_area(so.shape);
    const float r =
        static_cast<float>(std::sqrt(9.0 * area / (3.14159265358979323846 * static_cast<double>(n))));
    sr.cloud.radii.assign(sr.cloud.size(), r);
    pool::PoolWriter w;
    pre::write_point_sections(sr.cloud, w);
    auto points =
        std::make_shared<pool::PoolFile>(pool::PoolFile::from_bytes(w.serialize(), "synthetic room"));
    pre::OctreeStats stats;
    pre::OctreeParams params;
    params.max_leaf_splats = max_leaf;
    pre::SplatOctree tree =
        pre::build_octree(points->require<pool::Float3>(pool::SectionType::positions, "prt-bench"),
                          points->require<pool::Float3>(pool::SectionType::normals, "prt-bench"),
                          points->require<float>(pool::SectionType::radii, "prt-bench"), params, &stats);
    pool::PoolWriter w2;
    w2.carry_over(*points);
    pre::add_octree_sections(std::move(tree), w2);
    w2.add_provenance("prt-bench", PRT_VERSION,
                      "{\"synthetic\": \"room\", \"points\": " + std::to_string(n) + "}");
    tool::note(quiet,
               "prt-bench: synthetic room: %llu points, radius %.4g, octree depth %u, %u nodes, %llu splats "
               "stored (x%.2f), %.2f s",
               static_cast<unsigned long long>(n), r, stats.depth, stats.nodes,
               static_cast<unsigned long long>(stats.stored_splats), stats.replication_factor, stats.seconds);
    if (!save.empty()) {
        w2.write(save);
        tool::note(quiet, "prt-bench: wrote %s", save.string().c_str());
    }
    return std::make_shared<const pool::PoolFile>(
        pool::PoolFile::from_bytes(w2.serialize(), "synthetic room"));
}

rt::RenderScene bench_scene(const BenchSceneOptions& o, bool quiet) {
    rt::RenderScene rs;
    if (!o.pool.empty() || !o.scene.empty()) {
        rs = o.scene.empty() ? rt::RenderScene::from_pool(o.pool, o.load)
                             : rt::RenderScene::load(scene::load_scene(o.scene), o.pool, o.load);
    } else {
        scene::Scene sc;
        sc.materials.push_back(scene::Material{});
        sc.materials.back().name = "walls";
        sc.camera.position = {0, 0, 0.9};
        sc.camera.look_at = {0, -0.1, -1};
        sc.camera.fov_y_degrees = 60;
        scene::PointLight light;
        light.position = {0.2, 0.8, 0.3};
        sc.point_lights.push_back(light);
        // The synthetic room holds splats only: the load options refuse another surface.
        rs = rt::RenderScene::from_pools(
            sc, {synthetic_room_pool(o.synthetic, o.max_leaf, o.save_pool, quiet)}, o.load);
    }
    rs.scene().camera.width = o.width;
    rs.scene().camera.height = o.height;
    if (rs.lights().empty()) {
        scene::PointLight light;
        const auto lo = rs.world_min(), hi = rs.world_max();
        light.position = {hi[0], hi[1] + (hi[1] - lo[1]), hi[2]};
        rs.scene().point_lights.push_back(light);
        rs.update_lights();
    }
    return rs;
}

std::vector<BenchScenario> bench_scenarios(const core::RenderParams& base) {
    std::vector<BenchScenario> all;
    BenchScenario s{"primary", "primary rays, local shading, 1 light without shadows", base, false, 1.0};
    s.params.shadows = 0;
    s.params.max_bounces = 0;
    all.push_back(s);
    BenchScenario t{"shadow", "primary + 1 shadow ray per lit hit", base, false, 0.8};
    t.params.shadows = 1;
    t.params.max_bounces = 0;
    all.push_back(t);
    BenchScenario r{"reflect4", "primary + 4 bounces of reflection (reflectivity 0.8), no shadows", base,
                    true, 0.5};
    r.params.shadows = 0;
    r.params.reflections = 1;
    r.params.max_bounces = 4;
    r.params.min_ray_weight = 0.0f;  // every bounce is traced
    all.push_back(r);
    // Issue 5's second target: shadows and 4 bounces together (not run by default: --scenarios).
    BenchScenario f{"full4",
                    "primary + 4 bounces of reflection (reflectivity 0.8) + shadow rays at every hit", base,
                    true, 0.5};
    f.params.shadows = 1;
    f.params.reflections = 1;
    f.params.max_bounces = 4;
    f.params.min_ray_weight = 0.0f;
    all.push_back(f);
    return all;
}

std::vector<core::Material> scenario_materials(const BenchScenario& s,
                                               const std::vector<core::Material>& original) {
    std::vector<core::Material> mats = original;
    if (s.mirror) {
        for (core::Material& m : mats) {
            m.reflectivity = 0.8f;
            m.diffuse_reflectance = 0.2f;
            m.transmissivity = 0.0f;
        }
    }
    return mats;
}

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    const std::size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

}  // namespace prt::player
