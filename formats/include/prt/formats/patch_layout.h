// PointRT pool file: the Bezier patch sections (types 112-115, written by prt-patches, seed 002).
// Plain structs only: this header compiles under g++ and nvcc, and the core (prt/core/patch.h)
// reads the mapped section payloads through these structs without conversion.
//
// The mixed hierarchy of seed 002, 5.1: a BVH over the patches' bounding boxes, and under every
// patch a fixed-depth subpatch tree of boxes. All coordinates are in the model's local frame
// (world minus ModelInfo::origin).
//
//   patch_info (112)            one PatchInfo (64 B)
//   patch_control_points (113)  PatchControlNet[patch_count] (384 B each: 16 double control points)
//   patch_bvh (114)             PatchBvhNode[bvh_node_count] (32 B each), depth first:
//
//        node i (interior) -> left child i + 1, right child bvh[i + 1].skip,
//                             skip = first node after i's subtree (bvh_node_count for the last)
//        node i (leaf)     -> one patch; skip = i + 1
//
//        0 [root, skip=n] ---> 1 [A, skip=4] ---> 2 [leaf p, skip=3]
//                          |                 `--> 3 [leaf q, skip=4]
//                          `--> 4 [B, skip=n] ...
//
//   patch_subpatch_boxes (115)  SubpatchNode[patch_count * subpatch_nodes] (32 B each): per patch
//        a complete binary tree in level order (node k -> children 2k+1, 2k+2), so no pointers:
//
//        level 0         k = 0                 the whole patch, [0,1]^2
//        level 1         k = 1, 2              split along u at 1/2 (lower half first)
//        level 2         k = 3..6              each split along v at 1/2
//        level l         k = 2^l-1 .. 2^(l+1)-2  split along u when l-1 is even, v when odd
//        level depth     the 2^depth leaves: their parameter-space centres start Newton iteration
//
//        A node's parameter domain follows from its index alone (prt::core::subpatch_domain).
#pragma once

#include <cstddef>
#include <cstdint>

namespace prt::pool {

/// Deepest subpatch tree prt-patches builds (2^11 - 1 = 2047 nodes, 64 KiB per patch).
inline constexpr std::uint32_t k_max_subpatch_depth = 10;
/// Deepest BVH level (root = 0) a valid pool holds; sizes the traversal stack of prt/core/patch.h.
inline constexpr std::uint32_t k_max_patch_bvh_depth = 60;
/// Most patches one pool holds (patch indices are int32 in PatchBvhNode); prt-patches also keeps
/// patch_count * subpatch_nodes <= 2^31.
inline constexpr std::uint32_t k_max_patches = 1u << 22;

/// Patch-wide facts (section patch_info, exactly one element).
struct PatchInfo {
    std::uint32_t patch_count;     ///< 0: elements of patch_control_points
    std::uint32_t bvh_node_count;  ///< 4: elements of patch_bvh (2 * patch_count - 1)
    std::uint32_t subpatch_depth;  ///< 8: levels below the patch root (seed 002 uses 6)
    std::uint32_t subpatch_nodes;  ///< 12: boxes per patch, 2^(subpatch_depth + 1) - 1
    std::uint32_t bvh_depth;       ///< 16: deepest BVH level, root = 0 (at most k_max_patch_bvh_depth)
    std::uint32_t flags;           ///< 20: PatchFlags
    float bounds_min[3];           ///< 24: bounding box of all control points, local frame
    float bounds_max[3];           ///< 36
    std::uint32_t reserved[4];     ///< 48: 0
};
static_assert(sizeof(PatchInfo) == 64);
static_assert(offsetof(PatchInfo, flags) == 20);
static_assert(offsetof(PatchInfo, bounds_min) == 24);
static_assert(offsetof(PatchInfo, reserved) == 48);

/// PatchInfo::flags bits.
enum PatchFlags : std::uint32_t {
    /// prt-patches --orient made dQ/du x dQ/dv agree across every shared edge and point away from
    /// the model (a heuristic for open models). Only then do front/back tests (ray flags, back-face
    /// culling) mean anything; without it shade two-sided.
    k_patch_oriented = 1u << 0,
};

/// A control point in double precision (Newton iteration runs in double, seed 002, 5.3.3).
struct PatchPoint {
    double x, y, z;  ///< 0, 8, 16
};
static_assert(sizeof(PatchPoint) == 24);

/// The 4x4 control net of one bicubic Bezier patch, local frame:
///   Q(u, v) = sum_i sum_j B_i(u) B_j(v) p[4 * i + j],  B = cubic Bernstein polynomials,
/// i.e. row i of the source file's 4x4 net runs along v, rows advance along u.
struct PatchControlNet {
    PatchPoint p[16];  ///< 0: p[4 * i + j], i = u index, j = v index
};
static_assert(sizeof(PatchControlNet) == 384);

/// One BVH node (32 bytes; seed 002 stores 56 with double boxes: traversal runs in single
/// precision there too (section 6), so float boxes rounded outwards lose nothing).
struct PatchBvhNode {
    float lo[3];         ///< 0: box, local frame (rounded outwards from the double bounds)
    float hi[3];         ///< 12
    std::int32_t patch;  ///< 24: the patch of a leaf, -1 for an interior node
    std::uint32_t skip;  ///< 28: first node after this subtree (where a miss continues)
};
static_assert(sizeof(PatchBvhNode) == 32);
static_assert(offsetof(PatchBvhNode, patch) == 24);
static_assert(offsetof(PatchBvhNode, skip) == 28);

/// One subpatch tree node (32 bytes): the box of its control net (convex hull property) and a
/// cone bounding its normals dQ/du x dQ/dv, for conservative back-face culling (seed 002, 5.2).
struct SubpatchNode {
    float lo[3];              ///< 0: box, local frame (rounded outwards)
    float hi[3];              ///< 12
    std::uint32_t cone_axis;  ///< 24: unit cone axis, octahedral encoding (16 bits u, 16 bits v)
    float cone_cos;           ///< 28: cosine of the cone's half-angle, widened for the encoding
                              ///<     error; <= 0: normals span a half-space or more (never culled)
};
static_assert(sizeof(SubpatchNode) == 32);
static_assert(offsetof(SubpatchNode, cone_axis) == 24);
static_assert(offsetof(SubpatchNode, cone_cos) == 28);

}  // namespace prt::pool
