// PointRT pool file: the Bezier patch sections (types 112-115, patch_layout.h, written by
// prt-patches) of an opened pool, validated into typed views (formats/POOL.md, "Bezier patches").
// The runtime builds the core's PatchView from them (prt::rt::load_patch_view). Host only.
#pragma once

#include <span>

#include "prt/formats/patch_layout.h"
#include "prt/formats/pool.h"

namespace prt::pool {

/// The patch sections of a pool, validated: views into the mapped file, valid while the PoolFile lives.
struct PatchSections {
    PatchInfo info{};
    std::span<const PatchControlNet> nets;  ///< info.patch_count control nets
    std::span<const PatchBvhNode> bvh;      ///< info.bvh_node_count nodes, depth first
    std::span<const SubpatchNode> boxes;    ///< info.subpatch_nodes boxes per patch, patch after patch
};

/// Whether the pool holds any of the patch sections (112-115).
bool has_patches(const PoolFile& pool);

/// Validates patch_info, patch_control_points, patch_bvh and patch_subpatch_boxes: all present,
/// counts agreeing, finite values, boxes not inverted, cone cosines at most 1, the BVH a proper
/// depth-first tree with skip offsets over every patch exactly once, its depth as recorded and within
/// k_max_patch_bvh_depth. Throws prt::Error "FILE: section NAME: what is wrong".
PatchSections validate_patches(const PoolFile& pool);

}  // namespace prt::pool
