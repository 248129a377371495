// PointRT pool file: the splat octree sections (types 16-19, pool_layout.h, thesis 3.2) of an
// opened pool as typed views. PoolFile::open has already checked them (formats/POOL.md,
// "Validation" step 4), so reading them costs nothing. Host only.
#pragma once

#include <cstdint>
#include <span>

#include "prt/formats/pool.h"

namespace prt::pool {

/// The splat octree of a pool: views into the mapped file, valid while the PoolFile lives.
struct SplatOctreeSections {
    OctreeInfo info{};
    std::span<const std::uint32_t> nodes;      ///< info.node_count node words, node 0 the root
    std::span<const std::uint32_t> leaf_info;  ///< info.filled_leaves + 1 begin indices into splats
    std::span<const Splat> splats;             ///< info.splat_count splats, leaf-contiguous
};

/// Whether the pool holds the splat octree (open() accepts its four sections only together).
bool has_splat_octree(const PoolFile& pool);

/// The splat octree, as checked by open(). Throws prt::Error "FILE: section octree_info: missing
/// (needed by NEEDED_BY)" when the pool has none.
SplatOctreeSections splat_octree(const PoolFile& pool, const char* needed_by);

}  // namespace prt::pool
