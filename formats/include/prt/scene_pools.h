// PointRT: the pools of a scene step (prt-photons, prt-lightmap): the distinct pool files its
// models place, each rewritten once, in place, however often it is placed.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <vector>

#include "prt/formats/scene.h"

namespace prt::tool {

/// The distinct pools of a scene's models, in order of first placement.
struct ScenePools {
    std::vector<std::filesystem::path> paths;  ///< weakly canonical, one per pool file
    std::vector<std::uint32_t> of_model;       ///< per model: its pool's index in `paths`
    std::vector<bool> placed_before;           ///< per model: its pool was placed by an earlier model
    /// Per model: the key of its caustic and light maps (issue 20, formats/POOL.md "One map per
    /// placement"): 0 (any placement) when the scene places its pool once, else
    /// pool::placement_key(transform); models placing a pool at the same transform share a key.
    std::vector<std::uint32_t> map_key;
};

/// Groups the models of `sc` by pool file (std::filesystem::weakly_canonical paths); calls
/// `placed_again` (when given) with the pool of each model whose pool an earlier model placed, in
/// model order (for the step's note on what it does with such a pool).
ScenePools scene_pools(const scene::Scene& sc,
                       const std::function<void(const std::filesystem::path&)>& placed_again = {});

}  // namespace prt::tool
