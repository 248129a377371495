// PointRT runtime (host): the caustic octree (prt-photons, thesis 5.4) and light map
// (prt-lightmap, thesis 5.3) sections of a pool, validated by formats (prt/formats/gi_sections.h)
// and turned into the core's views (prt/core/gi.h). Layout: prt/formats/gi_layout.h; rules:
// formats/POOL.md.
#pragma once

#include "prt/core/gi.h"
#include "prt/formats/gi_sections.h"
#include "prt/formats/pool.h"

namespace prt::rt {

/// Whether the pool holds any caustic / light-map section.
using pool::has_caustics;
using pool::has_light_map;

/// The caustic sections (64-66) validated (pool::validate_caustic_maps) as a view into the mapped
/// pool (valid while the PoolFile lives): the map of the placement with key `placement`
/// (pool::placement_key; issue 20: a pool placed several times holds one map per placement), else
/// the map for any placement (key 0); an empty view (null nodes) when the pool has neither. Throws
/// prt::Error "FILE: section NAME: what is wrong" on any inconsistency.
core::CausticView load_caustic_view(const pool::PoolFile& pool, std::uint32_t placement = 0);
/// The same for the light-map sections (80-82; pool::validate_light_maps: one map per placement too).
core::LightMapView load_light_map_view(const pool::PoolFile& pool, std::uint32_t placement = 0);

}  // namespace prt::rt
