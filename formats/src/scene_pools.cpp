// The distinct pools of a scene and their placements (prt/scene_pools.h).
#include "prt/scene_pools.h"

#include <algorithm>
#include <filesystem>

#include "prt/formats/gi_sections.h"

namespace prt::tool {

ScenePools scene_pools(const scene::Scene& sc,
                       const std::function<void(const std::filesystem::path&)>& placed_again) {
    ScenePools pools;
    for (const scene::Model& m : sc.models) {
        const std::filesystem::path p = std::filesystem::weakly_canonical(m.pool);
        const auto it = std::find(pools.paths.begin(), pools.paths.end(), p);
        pools.of_model.push_back(static_cast<std::uint32_t>(it - pools.paths.begin()));
        pools.placed_before.push_back(it != pools.paths.end());
        if (it == pools.paths.end())
            pools.paths.push_back(p);
        else if (placed_again)
            placed_again(p);
    }
    std::vector<std::uint32_t> placements(pools.paths.size(), 0);
    for (const std::uint32_t p : pools.of_model) ++placements[p];
    for (std::size_t m = 0; m < sc.models.size(); ++m)
        pools.map_key.push_back(
            placements[pools.of_model[m]] > 1 ? pool::placement_key(sc.models[m].transform) : 0u);
    return pools;
}

}  // namespace prt::tool
