// PointRT pool file: the caustic octree (types 64-66, prt-photons) and light map (types 80-82,
// prt-lightmap) sections of an opened pool, validated into typed views (gi_layout.h; rules in
// formats/POOL.md, "Caustics and light maps"). The runtime builds the core's CausticView and
// LightMapView from them (prt::rt::load_caustic_view, load_light_map_view). Host only.
#pragma once

#include <cstdint>
#include <optional>
#include <span>

#include "prt/formats/gi_layout.h"
#include "prt/formats/pool.h"

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

/// Validates the caustic sections: the three come together, exactly one GiInfo, root corner finite,
/// edge finite and positive, depth at most k_max_gi_depth, counts matching the arrays, gather radius
/// and scale finite and positive, normal threshold in [-1, 1], the nodes a proper tree from node 0
/// (children after their parent, every node reached once, no internal node at depth, every filled
/// leaf at depth, each leaf addressed exactly once). Returns nothing when the pool has none of them;
/// throws prt::Error "FILE: section NAME: what is wrong" on the first problem.
std::optional<GiSections> validate_caustics(const PoolFile& pool);
/// The same for the light-map sections.
std::optional<GiSections> validate_light_map(const PoolFile& pool);

}  // namespace prt::pool
