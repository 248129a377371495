// PointRT pool file: the caustic octree (types 64-66, prt-photons) and light map (types 80-82,
// prt-lightmap) sections of an opened pool, validated into typed views (gi_layout.h; rules in
// formats/POOL.md, "Caustics and light maps"). The runtime builds the core's CausticView and
// LightMapView from them (prt::rt::load_caustic_view, load_light_map_view). Host only.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "prt/formats/gi_layout.h"
#include "prt/formats/pool.h"
#include "prt/formats/scene.h"

namespace prt::pool {

/// The three sections of one map, validated: views into the mapped file, valid while the PoolFile lives.
struct GiSections {
    GiInfo info{};
    std::span<const std::uint32_t> nodes;  ///< info.node_count node words, node 0 the root
    std::span<const GiLeaf> leaves;        ///< info.leaf_count leaves
};

/// Whether the pool holds any caustic / light-map section.
bool has_caustics(const PoolFile& pool);
bool has_light_map(const PoolFile& pool);

/// The key of a scene placement (issue 20: one caustic map and one light map per placement of a
/// pool): a hash of the
/// model's transform (translate, rotate_degrees, scale as doubles, XXH3-64 folded to 32 bits), never 0.
std::uint32_t placement_key(const scene::Transform& t);

/// Validates the caustic sections (issue 20: one map per placement): caustic_info holds one GiInfo
/// per map, caustic_nodes and caustic_leaves their arrays one after the other in that order; each
/// map is checked as validate_caustics says; with more than one map, every map's placement key is
/// non-zero and distinct. Returns no map when the pool has none of the sections.
std::vector<GiSections> validate_caustic_maps(const PoolFile& pool);

/// The same for the light-map sections (light_map_info: one GiInfo per map, one map per placement).
std::vector<GiSections> validate_light_maps(const PoolFile& pool);

/// The map of validate_caustic_maps() or validate_light_maps() for the placement with key
/// `placement`: the map with that key, else one with key 0 (any placement); nullptr when there is
/// neither.
const GiSections* find_gi_map(const std::vector<GiSections>& maps, std::uint32_t placement);

/// Validates the caustic sections of a pool holding one map (or none): the three come together,
/// exactly one GiInfo, root corner finite,
/// edge finite and positive, depth at most k_max_gi_depth, counts matching the arrays, gather radius
/// and scale finite and positive, normal threshold in [-1, 1], the nodes a proper tree from node 0
/// (children after their parent, every node reached once, no internal node at depth, every filled
/// leaf at depth, each leaf addressed exactly once). Returns nothing when the pool has none of them;
/// throws prt::Error "FILE: section NAME: what is wrong" on the first problem.
std::optional<GiSections> validate_caustics(const PoolFile& pool);
/// The same for the light-map sections.
std::optional<GiSections> validate_light_map(const PoolFile& pool);

}  // namespace prt::pool
