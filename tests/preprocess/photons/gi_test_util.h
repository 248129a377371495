// Test helpers for prt-photons and prt-lightmap: scenes of analytic point sets (tests/runtime/
// test_scene.h) as in-memory pools or pool files, loaded as a RenderScene.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "prt/formats/pool.h"
#include "prt/formats/scene.h"
#include "prt/runtime/render_scene.h"
#include "runtime/test_scene.h"

namespace prt::test {

/// A scene of in-memory pools: `json` is a scene file whose models name the pools by index order.
struct GiScene {
    std::vector<TestModel> models;
    std::vector<std::shared_ptr<const pool::PoolFile>> pools;
    rt::RenderScene scene;
};

inline rt::RenderScene load_gi_scene(const std::string& json,
                                     const std::vector<std::shared_ptr<const pool::PoolFile>>& pools) {
    const scene::Scene sc = scene::parse_scene(json, "test scene");
    return rt::RenderScene::from_pools(sc, pools);
}

/// The closed white room of the light-map tests (a sphere of radius 1, normals inward, albedo 0.5)
/// lit by `lights` (a JSON array), traced as `surface`.
inline rt::RenderScene white_room(const std::string& lights,
                                  const std::shared_ptr<const pool::PoolFile>& pool,
                                  const std::string& surface = "splats") {
    return test::load_gi_scene(R"({"lights": )" + lights + R"(,
        "materials": [{"name": "white", "diffuse": [0.5, 0.5, 0.5], "specular": [0, 0, 0], "diffuse_reflectance": 1,
                       "use_point_colors": false}],
        "models": [{"name": "room", "pool": "room.pool", "surface": ")" +
                                   surface + R"("}],
        "environment": {"color": [0, 0, 0]}})",
                               {pool});
}

/// Writes a test model's pool to `path` (atomic writer).
inline void write_model_pool(const TestModel& m, const std::filesystem::path& path, bool colors = true) {
    const auto in = make_pool(m, colors);
    pool::PoolWriter w;
    w.carry_over(*in);
    w.write(path);
}

/// A fresh empty folder under the system temp dir.
inline std::filesystem::path fresh_dir(const std::string& name) {
    const std::filesystem::path d =
        std::filesystem::temp_directory_path() / ("prt_gi_" + name + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(d);
    std::filesystem::create_directories(d);
    return d;
}

}  // namespace prt::test
