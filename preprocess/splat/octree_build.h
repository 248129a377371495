// PointRT preprocess: the splat octree builder (thesis 2.2, 3.1, 3.2) shared by prt-octree, the
// tests and benchmarks. Produces exactly the pool sections octree_info, octree_nodes, leaf_info,
// splats (layout: formats/include/prt/formats/pool_layout.h).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "prt/formats/pool.h"

namespace prt::pre {

struct OctreeParams {
    std::uint32_t max_leaf_splats = 16;  ///< X of thesis 3.2: a leaf holding more is split
    std::uint32_t max_depth = 24;        ///< leaves at this level are never split
    bool replicate = true;               ///< store each splat in every leaf its disk overlaps
};

struct OctreeStats {
    std::uint32_t nodes = 0, depth = 0, filled_leaves = 0, empty_leaves = 0;
    std::uint64_t unique_splats = 0, stored_splats = 0;
    double replication_factor = 0;  ///< stored / unique
    double seconds = 0;
};

/// A built octree, ready to be added to a pool (add_octree_sections()).
struct SplatOctree {
    pool::OctreeInfo info{};
    std::vector<std::uint32_t> nodes;
    std::vector<std::uint32_t> leaf_info;  ///< filled_leaves + 1 entries
    std::vector<pool::Splat> splats;
};

/// Builds the octree over splats given in the model's local frame. Points whose radius is not
/// finite and positive are skipped (and counted in stats). Throws prt::Error if the node count
/// would exceed the 30-bit address range.
SplatOctree build_octree(std::span<const pool::Float3> positions, std::span<const pool::Float3> normals,
                         std::span<const float> radii, const OctreeParams& params,
                         OctreeStats* stats = nullptr);

/// Adds (replacing) the four octree sections to a writer.
void add_octree_sections(SplatOctree octree, pool::PoolWriter& writer);

}  // namespace prt::pre
