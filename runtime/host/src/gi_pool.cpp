// PointRT runtime (host): the caustic and light-map sections, validated by formats
// (prt/formats/gi_sections.h), as the core's views.
#include "prt/runtime/gi_pool.h"

#include <vector>

namespace prt::rt {

namespace {

core::GiOctreeView make_view(const pool::GiSections* s) {
    core::GiOctreeView v;
    if (s == nullptr) return v;
    v.nodes = s->nodes.data();
    v.node_count = static_cast<std::uint32_t>(s->nodes.size());
    v.leaves = s->leaves.data();
    v.leaf_count = static_cast<std::uint32_t>(s->leaves.size());
    v.depth = s->info.depth;
    v.root_min = core::Vec3{s->info.root_min[0], s->info.root_min[1], s->info.root_min[2]};
    v.root_size = s->info.root_size;
    v.inv_root_size = 1.0f / s->info.root_size;
    v.scale = s->info.scale;
    v.cos_threshold = s->info.cos_threshold;
    return v;
}

}  // namespace

core::CausticView load_caustic_view(const pool::PoolFile& pool, std::uint32_t placement) {
    const std::vector<pool::GiSections> maps = pool::validate_caustic_maps(pool);
    return core::CausticView{make_view(pool::find_gi_map(maps, placement))};
}

core::LightMapView load_light_map_view(const pool::PoolFile& pool, std::uint32_t placement) {
    const std::vector<pool::GiSections> maps = pool::validate_light_maps(pool);
    return core::LightMapView{make_view(pool::find_gi_map(maps, placement))};
}

}  // namespace prt::rt
