// PointRT pool file: the exact MLS surface sections (types 48-53, mls_layout.h, written by prt-mls)
// of an opened pool, validated into typed views (formats/POOL.md, "MLS surface"). The runtime builds
// the core's MlsView from them (prt::rt::load_mls_view). Host only.
#pragma once

#include <cstdint>
#include <span>

#include "prt/formats/mls_layout.h"
#include "prt/formats/pool.h"

namespace prt::pool {

/// The MLS sections of a pool, validated: views into the mapped file, valid while the PoolFile lives.
struct MlsSections {
    MlsInfo info{};
    std::span<const MlsNode> nodes;       ///< info.node_count kd-tree nodes, node 0 the root
    std::span<const std::uint32_t> refs;  ///< info.ref_count splat indices, leaf after leaf
    std::span<const MlsSplat> splats;     ///< info.splat_count splats
    std::span<const MlsBvhNode> bvh_nodes;  ///< the BVH over the non-empty leaves (empty: none)
    std::span<const MlsBvhLeaf> bvh_leaves;
};

/// Whether the pool holds any of the MLS sections (48-53).
bool has_mls(const PoolFile& pool);

/// Validates the four MLS sections: all present, exactly one MlsInfo, counts agreeing, finite
/// values, supports > 0, point indices below ModelInfo::point_count, refs in range, the nodes a
/// proper tree from node 0 (children after their parent, every node reached once, split planes
/// inside their cell), leaves covering mls_refs exactly once, depth and leaf count as recorded,
/// depth at most k_max_mls_depth; the optional BVH (52-53) as check_mls_bvh says: its leaves the
/// kd-tree's non-empty leaves, its boxes holding what lies under them. Throws prt::Error "FILE: section NAME:
/// what is wrong".
MlsSections validate_mls(const PoolFile& pool);

}  // namespace prt::pool
