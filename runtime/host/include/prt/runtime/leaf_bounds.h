// PointRT runtime (host): the per-leaf bounds (core::LeafBounds, prt/core/octree.h) that let rays
// pass a filled leaf without reading its splats. Derived from the pool's octree sections when a
// scene is loaded: they are not stored in the pool.
#pragma once

#include <vector>

#include "prt/core/bricks.h"
#include "prt/core/octree.h"

namespace prt::rt {

/// Builds one LeafBounds per filled leaf of `v` (v.leaf_bounds is not read): the normal cone
/// (axis = the mean unit normal, half-angle = the widest normal from it), the slab of the disks
/// along that axis, computed in double and widened by rounding margins so the core's tests stay
/// conservative, and the leaf's splat range (leaf_info, clamped as core::leaf_splats clamps).
/// Splats that the core can never hit (zero or NaN radius or normal) are left out; a splat with
/// non-finite data turns the leaf's tests off. Uses up to `threads` threads (0: all hardware
/// threads).
std::vector<core::LeafBounds> build_leaf_bounds(const core::OctreeView& v, unsigned threads = 0);

/// A line through a node's cell meets the node's box with a chance of (the surface area of the box
/// inside the cell) / (the cell's); a child is tested (NodeBoxes::mask) below this chance. Set on
/// the H200 (2026-12-03): walls' nodes in the culled 1M room have 0.33 (median), the culled
/// spheres' 0.80-0.82, where testing every node cost 1-10 % (preprocess/bench/results/
/// h200-2026-12-03-issue19-io-boxes).
inline constexpr double k_node_box_test_below = 0.5;

/// core::OctreeView::node_boxes and node_box_mask of an octree (both empty: none).
struct NodeBoxes {
    std::vector<core::NodeBox> boxes;
    std::vector<std::uint8_t> mask;
};

/// The NodeBox of every internal node of `v` (core::OctreeView::node_boxes: indexed by the node's
/// children block, (address - 1) / 8): the axis-aligned box, in normalized root coordinates, of
/// every hittable disk stored in the node's leaves, rounded outward to float; and the mask of the
/// children worth a test (k_node_box_test_below). A leaf with non-finite splats makes its
/// ancestors' boxes infinite (never skipped). Empty when the node pool is not laid out as the
/// walk's index assumes (children blocks of 8 after the root, each behind its parent): the scene
/// then renders without node boxes. Uses up to `threads` threads (0: all).
NodeBoxes build_node_boxes(const core::OctreeView& v, unsigned threads = 0);

/// Macro-regions (core::MacroRegion) of the empty leaves at levels 1 .. k_macro_region_levels:
/// deeper leaves (and every other node) get none, all zero. The regions are grown on a grid of cells
/// at level min(depth, k_macro_region_levels) marked where a leaf holding splats reaches (3D prefix
/// sums: a box of cells is free when its count is 0; a free box at a level no deeper than the
/// grid's is exactly one that no such leaf meets). A tree without leaf_info (core::IsoView::tree:
/// an ISO, where every filled leaf holds surface) counts every filled leaf. Level 8 by measurement:
/// on the culled 1M room's ISO (depth 10), grids at levels 9 and 10 cut the leaves per primary ray
/// from 9.7 to 9.2 only and took 0.7 and 4.3 GB while loading (2026-12-06, dev VM).
inline constexpr std::uint32_t k_macro_region_levels = 8;

/// core::OctreeView::macro_regions and the node pool that indexes it (both empty: none).
struct MacroRegions {
    std::vector<std::uint32_t> nodes;        ///< the node pool, empty leaves' address = their region
    std::vector<core::MacroRegion> regions;  ///< k_region_axes per address; address 0's unused (all zero)
};

/// The macro-regions of `v`'s empty leaves (core::MacroRegion), core::k_region_axes per leaf:
/// region a is the leaf's cell grown greedily along axis a first (both ways, as far as it goes),
/// then axis by axis in turn (x-, x+, y-, y+, z-, z+), by doubling steps of cells at its level while
/// the box stays free and, once a step fails, by halving ones (a binary search for the last free
/// slab), up to 255 cells each way and inside the root. Only leaves with a region more than their
/// cell get them (an address in `nodes`; other empty leaves' addresses are 0 there, other words are
/// the pool's). Empty when the node pool
/// is not laid out as build_node_boxes requires, or the tree is a single leaf. Uses up to `threads` threads
/// (0: all).
MacroRegions build_macro_regions(const core::OctreeView& v, unsigned threads = 0);

/// The compact bounds (core::BrickLeafBounds, 16 bytes: the same cone and slab about an integer
/// axis, no splat range) of every filled leaf of every brick of a bricked pool (issue 17), over each
/// brick's decoded splats (the ones the core intersects); brick b's leaves start at `first[b]`
/// (brick_count + 1 entries, set here). Every brick must be resident.
std::vector<core::BrickLeafBounds> build_brick_leaf_bounds(const core::BrickView& v,
                                                           std::vector<std::uint32_t>& first,
                                                           unsigned threads = 0);

/// The same for one brick alone (streaming: computed when the brick is uploaded, from its payload
/// only): entry.leaf_count bounds, equal to that brick's part of build_brick_leaf_bounds.
/// `payload` must be a validated payload of this entry.
std::vector<core::BrickLeafBounds> build_one_brick_leaf_bounds(const pool::BrickEntry& entry,
                                                               const unsigned char* payload);

}  // namespace prt::rt
