// PointRT: the patch sections of a pool, validated, as the core's PatchView (host pointers into
// the mapped file). Every cross-reference the traversal relies on is checked here, so a bad pool
// gives a one-line error instead of a crash or an endless loop.
#pragma once

#include "prt/core/patch.h"
#include "prt/formats/pool.h"

namespace prt::patches {

/// Whether the pool holds any of the patch sections.
bool has_patches(const pool::PoolFile& pool);

/// Validates patch_info, patch_control_points, patch_bvh and patch_subpatch_boxes (all present,
/// counts agreeing, finite values, boxes not inverted, the BVH a proper depth-first tree with skip
/// offsets over every patch exactly once, its depth within pool::k_max_patch_bvh_depth) and returns
/// the view. Throws prt::Error "FILE: section NAME: what is wrong" otherwise.
core::PatchView load_patch_view(const pool::PoolFile& pool);

}  // namespace prt::patches
