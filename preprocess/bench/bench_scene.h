// PointRT benchmarks: the scene and scenarios prt-bench times, shared with the Embree peer
// benchmark (preprocess/bench) so that both render the same splats from the same view.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "prt/core/scene_view.h"
#include "prt/formats/pool.h"
#include "prt/runtime/render_scene.h"

namespace CLI {
class App;
}

namespace prt::player {

/// Where the benchmark scene comes from.
struct BenchSceneOptions {
    std::filesystem::path pool;         ///< a pool (with --scene: replaces the scene's models)
    std::filesystem::path scene;        ///< a scene file
    std::uint64_t synthetic = 1000000;  ///< points of the synthetic room (no pool and no scene)
    std::uint32_t max_leaf = 32;        ///< the synthetic room's octree: splats per leaf before a split
    std::filesystem::path save_pool;    ///< also write the synthetic room's pool here
    rt::LoadOptions load;               ///< surface choice (--surface, --iso-float)
    std::uint32_t width = 1024, height = 1024;
};

/// Declares the scene options prt-bench and prt-bench-embree share, in this order: the positional
/// `pool` (help `pool_help`), --scene, --synthetic, --max-leaf (help `max_leaf_help`), --save-pool
/// (only with `save_pool`), --width and --height.
void add_scene_options(CLI::App& app, BenchSceneOptions& o, const char* pool_help, const char* max_leaf_help,
                       bool save_pool);

/// The synthetic benchmark pool: prt-synth's room (a closed box with a sphere and a cube) of `n`
/// points, splat radii from the sampling density (thesis 3.1's k-NN radius for k = 9 at uniform
/// density), and prt-octree's builder with `max_leaf` splats per leaf.
std::shared_ptr<const pool::PoolFile> synthetic_room_pool(std::uint64_t n, std::uint32_t max_leaf,
                                                          const std::filesystem::path& save, bool quiet);

/// The benchmark scene: the given pool and/or scene file, or the synthetic room seen from inside
/// (every primary ray hits) with one light; a scene without lights gets one above the models.
rt::RenderScene bench_scene(const BenchSceneOptions& o, bool quiet);

/// One timed scenario.
struct BenchScenario {
    std::string name;
    std::string what;
    core::RenderParams params;
    bool mirror = false;  ///< every material becomes a mirror (reflectivity 0.8)
    double target_grays = 0;
};

/// The three scenarios over `base`: primary (local shading, no shadows), shadow (one
/// shadow ray per lit hit and light), reflect4 (every surface a mirror, 4 bounces, every bounce
/// traced).
std::vector<BenchScenario> bench_scenarios(const core::RenderParams& base);

/// The materials a scenario renders with (reflect4 turns every material into a mirror).
std::vector<core::Material> scenario_materials(const BenchScenario& s,
                                               const std::vector<core::Material>& original);

/// Median of a sample (0 when empty).
double median(std::vector<double> v);

}  // namespace prt::player
