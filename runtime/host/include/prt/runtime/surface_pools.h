// PointRT runtime (host): the ISO, MLS and patch sections of a pool, validated, as the core's
// views (host pointers into the mapped file; the CUDA backend copies the same bytes to the GPU).
// Each load_* throws prt::Error "FILE: section NAME: what is wrong" on a bad pool.
#pragma once

#include <cstdint>

#include "prt/core/iso.h"
#include "prt/core/mls.h"
#include "prt/core/patch.h"
#include "prt/formats/pool.h"

namespace prt::rt {

/// Whether the pool holds any of the ISO sections (32-35).
bool has_iso(const pool::PoolFile& pool);
/// Validates the ISO sections (iso_info and iso_nodes present, exactly one IsoInfo, the leaf arrays
/// IsoInfo's flags name present with leaf_count elements and no others, root cube finite with a
/// positive edge, levels within pool::k_max_iso_level, the nodes a proper tree from node 0 with
/// every child group after its parent and reached once, depth as recorded, every filled leaf
/// addressing a distinct leaf in range and every leaf addressed, float values and normals finite)
/// and returns the view (quantized leaves preferred when `prefer_q8` and present).
core::IsoView load_iso_view(const pool::PoolFile& pool, bool prefer_q8 = true);
/// The view over ISO arrays already in memory (no validation).
core::IsoView make_iso_view(const pool::IsoInfo& info, const std::uint32_t* nodes, const pool::IsoLeafQ8* q8,
                            const pool::IsoLeafF32* f32, bool prefer_q8);

/// Whether the pool holds any of the MLS sections (48-51).
bool has_mls(const pool::PoolFile& pool);
/// Validates the four MLS sections (all present, exactly one MlsInfo, counts agreeing, finite
/// values, supports > 0, point indices below ModelInfo::point_count, refs in range, the nodes a
/// proper tree from node 0 with children after their parent, every node reached once, split
/// planes inside their cell, leaves covering mls_refs exactly once, depth as recorded and at most
/// pool::k_max_mls_depth) and returns the view.
core::MlsView load_mls_view(const pool::PoolFile& pool);
/// The view over MLS arrays already in memory (counts from `info`; no validation).
core::MlsView make_mls_view(const pool::MlsInfo& info, const pool::MlsNode* nodes, const std::uint32_t* refs,
                            const pool::MlsSplat* splats);

/// Whether the pool holds any of the patch sections (112-115).
bool has_patches(const pool::PoolFile& pool);
/// Validates patch_info, patch_control_points, patch_bvh and patch_subpatch_boxes (all present,
/// counts agreeing, finite values, boxes not inverted, the BVH a proper depth-first tree with skip
/// offsets over every patch exactly once, its depth within pool::k_max_patch_bvh_depth) and returns
/// the view.
core::PatchView load_patch_view(const pool::PoolFile& pool);

}  // namespace prt::rt
