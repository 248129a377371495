// PointRT pool file: the exact MLS surface sections (types 48-53, written by prt-mls, Wald & Seidel
// 2005, "WS05"). Plain structs only: this header compiles under g++ and nvcc, and the core
// (prt/core/mls.h) reads the mapped section payloads through these structs without conversion.
//
// The surface is Adamson and Alexa's implicit surface F(x) = 0 (WS05 3.1.1, eq. 1-2) over the
// splats of mls_splats; a kd-tree (WS05 3.4) whose leaves reference every splat whose spherical
// support overlaps them tells a ray which splats to sum in each cell. All coordinates are in the
// model's local frame (world minus ModelInfo::origin).
//
//   mls_info (48)    one MlsInfo (64 B): root box, counts, depth, build parameters and flags
//   mls_nodes (49)   MlsNode[node_count] (8 B each), node 0 the root, children in pairs:
//
//        inner node i:  payload = split position (float bits), meta = (left << 2) | axis
//                       left child = nodes[left], right child = nodes[left + 1], left > i
//                       left child: x[axis] <= split, right child: x[axis] >= split
//        leaf:          payload = first ref, meta = (count << 2) | 3
//                       its splats are splats[refs[first .. first + count)]; count 0 = empty
//
//        0 [x < 0.2 | x > 0.2] --> 1 [leaf, refs 0..12]
//                              `-> 2 [y < -0.1 | ...] --> 3 [empty leaf]     (a shrinking split,
//                                                     `-> 4 ...                WS05 3.4.1)
//
//   mls_refs (50)    uint32 splat indices, leaf after leaf (a splat appears in every leaf its
//                    support overlaps)
//   mls_splats (51)  MlsSplat[splat_count] (32 B each): position, 1 / support radius, normal,
//                    index of the source point (colors, material ids)
//   mls_bvh_nodes (52), mls_bvh_leaves (53), optional (prt-mls since 2026-12-03, both or neither):
//                    a binary BVH over the kd-tree's non-empty leaves, for the ray walk. Each leaf
//                    (MlsBvhLeaf, 32 B) is one non-empty kd leaf: its cell and refs; each node
//                    (MlsBvhNode, 64 B) holds its two children's boxes (a leaf's: its cell cut to
//                    the box of its splats' support balls) and references. A ray crossing the empty
//                    inside of a room passes dozens of empty kd cells (prt-synth's room: 274 kd
//                    nodes a primary ray, 54 leaves, 1.1 of them sampled); the BVH skips the empty
//                    space in 26 node visits and samples the same cells over the same intervals.
//
//        node 0 [box A | box B]  -->  A: node 1 [box C | box D]  -->  C: leaf 7 (cell, refs)
//                                `->  B: leaf 3                   `->  D: ...
#pragma once

#include <cstddef>
#include <cstdint>

#include "prt/formats/pool_layout.h"

/// The node helpers below are called from the core's kernels too (this header does not see
/// prt/core/config.h): host + device under nvcc.
#if defined(__CUDACC__)
#define PRT_MLS_LAYOUT_HD __host__ __device__
#else
#define PRT_MLS_LAYOUT_HD
#endif

namespace prt::pool {

/// Deepest kd-tree level (root = 0) a valid pool holds; sizes the traversal stack of
/// prt/core/mls.h (one entry per level).
inline constexpr std::uint32_t k_max_mls_depth = 64;
/// Deepest BVH node level a valid pool holds (root = 0); sizes the BVH walk's stack.
inline constexpr std::uint32_t k_max_mls_bvh_depth = 64;
/// MlsBvhChild::ref bit marking a leaf (the low 31 bits index mls_bvh_leaves, else mls_bvh_nodes).
inline constexpr std::uint32_t k_mls_bvh_leaf_bit = 1u << 31;
/// Largest node index / ref count a node word holds (30 bits).
inline constexpr std::uint32_t k_mls_index_max = (1u << 30) - 1u;
/// MlsNode::meta axis value of a leaf.
inline constexpr std::uint32_t k_mls_leaf = 3u;

/// Surface-wide facts (section mls_info, exactly one element).
struct MlsInfo {
    float root_lo[3];           ///< 0: root cell: the box of every splat's support, local frame
    float root_hi[3];           ///< 12
    std::uint32_t node_count;   ///< 24: elements of mls_nodes
    std::uint32_t ref_count;    ///< 28: elements of mls_refs
    std::uint32_t splat_count;  ///< 32: elements of mls_splats (points with a usable radius)
    std::uint32_t depth;        ///< 36: deepest node level, root = 0 (at most k_max_mls_depth)
    float support_factor;       ///< 40: support radius = support_factor x splat radius (prt-radii)
    std::uint32_t samples;      ///< 44: samples per cell interval the tree was built for (WS05 3.2.2)
    std::uint32_t flags;        ///< 48: MlsFlags
    std::uint32_t leaf_count;   ///< 52: leaves, empty ones included
    std::uint32_t bvh_depth;    ///< 56: deepest BVH node level, root = 0 (0 without the BVH sections)
    std::uint32_t reserved;     ///< 60: 0
};
static_assert(sizeof(MlsInfo) == 64);
static_assert(offsetof(MlsInfo, node_count) == 24);
static_assert(offsetof(MlsInfo, support_factor) == 40);
static_assert(offsetof(MlsInfo, flags) == 48);
static_assert(offsetof(MlsInfo, bvh_depth) == 56);

/// MlsInfo::flags bits: which kd-tree optimizations of WS05 3.4 the build used.
enum MlsFlags : std::uint32_t {
    k_mls_shrunk = 1u << 0,      ///< 3.4.1 cell shrinking (interval arithmetic, conservative)
    k_mls_encouraged = 1u << 1,  ///< 3.4.2 encouraged splits, E(n) in the SAH
    k_mls_collapsed = 1u << 2,   ///< 3.4.3 post-collapse of splits with two empty children
};

/// One kd-tree node (8 bytes: WS05 follows [Wal04]'s compact nodes, two per 16-byte pair of
/// siblings, so a traversal step touches one cache line).
struct MlsNode {
    std::uint32_t payload;  ///< 0: inner: split position as float bits; leaf: first index into mls_refs
    std::uint32_t meta;     ///< 4: bits 1..0 axis (0, 1, 2) or k_mls_leaf; bits 31..2 left child / ref count
};
static_assert(sizeof(MlsNode) == 8);
static_assert(offsetof(MlsNode, meta) == 4);

/// One splat of the MLS surface (32 bytes).
struct MlsSplat {
    Float3 position;      ///< 0: p_i, local frame
    float inv_support;    ///< 12: 1 / R_i, R_i the support radius (weight w_i = W(|x - p_i| / R_i))
    Float3 normal;        ///< 16: n_i, unit
    std::uint32_t point;  ///< 28: index of the source point (colors, material_ids)
};
static_assert(sizeof(MlsSplat) == 32);
static_assert(offsetof(MlsSplat, normal) == 16);
static_assert(offsetof(MlsSplat, point) == 28);

/// One child of a BVH node (32 bytes, one read-only load pair on the GPU): the box a ray must meet
/// to reach anything under it, and where it is.
struct MlsBvhChild {
    float lo[3];             ///< 0: box, local frame (rounded outwards): the union of the leaves' boxes below
    float hi[3];             ///< 12
    std::uint32_t ref;       ///< 24: k_mls_bvh_leaf_bit | leaf index, or a node index (> its parent's)
    std::uint32_t reserved;  ///< 28: 0
};
static_assert(sizeof(MlsBvhChild) == 32);
static_assert(offsetof(MlsBvhChild, ref) == 24);

/// One BVH node (64 bytes): its two children. Node 0 is the root; the tree has leaf_count - 1 nodes.
struct MlsBvhNode {
    MlsBvhChild child[2];
};
static_assert(sizeof(MlsBvhNode) == 64);

/// One BVH leaf (32 bytes): a non-empty kd leaf's cell, exactly as the kd-tree's splits bound it
/// (the ray samples the same interval as the kd walk would), and its refs.
struct MlsBvhLeaf {
    float lo[3];          ///< 0: the kd cell
    float hi[3];          ///< 12
    std::uint32_t first;  ///< 24: first index into mls_refs (the kd leaf's)
    std::uint32_t count;  ///< 28: refs (> 0)
};
static_assert(sizeof(MlsBvhLeaf) == 32);
static_assert(offsetof(MlsBvhLeaf, first) == 24);

/// Node word helpers (host and device: plain constexpr integer operations).
PRT_MLS_LAYOUT_HD inline constexpr std::uint32_t mls_node_axis(const MlsNode& n) {
    return n.meta & 3u;
}
PRT_MLS_LAYOUT_HD inline constexpr bool mls_node_is_leaf(const MlsNode& n) {
    return (n.meta & 3u) == k_mls_leaf;
}
/// Left child of an inner node (the right child is the next node).
PRT_MLS_LAYOUT_HD inline constexpr std::uint32_t mls_node_left(const MlsNode& n) {
    return n.meta >> 2;
}
/// First ref / ref count of a leaf.
PRT_MLS_LAYOUT_HD inline constexpr std::uint32_t mls_leaf_first(const MlsNode& n) {
    return n.payload;
}
PRT_MLS_LAYOUT_HD inline constexpr std::uint32_t mls_leaf_count(const MlsNode& n) {
    return n.meta >> 2;
}
PRT_MLS_LAYOUT_HD inline constexpr MlsNode make_mls_leaf(std::uint32_t first, std::uint32_t count) {
    return MlsNode{first, (count << 2) | k_mls_leaf};
}
/// An inner node from the split position's float bits (std::bit_cast on the host).
PRT_MLS_LAYOUT_HD inline constexpr MlsNode make_mls_inner(std::uint32_t split_bits, std::uint32_t axis,
                                                          std::uint32_t left) {
    return MlsNode{split_bits, (left << 2) | (axis & 3u)};
}

}  // namespace prt::pool
