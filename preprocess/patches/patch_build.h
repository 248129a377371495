// prt-patches: building the mixed hierarchy of seed 002, 5.1 (a BVH over the patches by binned
// SAH, depth first with skip offsets; a fixed-depth subpatch tree of boxes and normal cones under
// every patch) and the optional orientation of the patches' u/v order.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "prt/formats/patch_layout.h"
#include "prt/formats/pool.h"
#include "prt/formats/pool_layout.h"

namespace prt::patches {

/// An axis-aligned box in double precision.
struct Box {
    double lo[3] = {0, 0, 0};
    double hi[3] = {0, 0, 0};
};

/// Bounds of the 16 control points (contains the patch: convex hull property).
Box net_bounds(const pool::PatchControlNet& net);

/// float bounds containing [lo, hi] (each bound rounded outwards).
void round_outwards(const Box& box, float lo[3], float hi[3]);

/// Swaps u and v (transposes the control net): the same surface with dQ/du x dQ/dv negated.
pool::PatchControlNet transpose_net(const pool::PatchControlNet& net);

/// What orient_patches found and did.
struct OrientStats {
    std::uint32_t components = 0;         ///< groups of patches connected through shared edges
    std::uint32_t flipped = 0;            ///< patches transposed
    std::uint32_t shared_edges = 0;       ///< edges shared by exactly two patches
    std::uint32_t boundary_edges = 0;     ///< edges of one patch only
    std::uint32_t nonmanifold_edges = 0;  ///< edges of three or more patches (ignored)
    std::uint32_t collapsed_edges = 0;    ///< edges whose 4 control points coincide (degenerate patches)
    std::uint32_t conflicts = 0;          ///< shared edges still inconsistent (non-orientable)
    std::uint32_t flat_components =
        0;  ///< groups with no inside (signed volume ~ 0): file's orientation kept
};

/// Makes dQ/du x dQ/dv consistent across shared edges (two patches sharing an edge run it in
/// opposite directions) by transposing patches, then turns each connected group outwards: the
/// sign of the integral of (Q - centre) . (dQ/du x dQ/dv) over the group, with the model's box
/// centre, is made positive (for a closed group that is its volume; for an open one, "facing away
/// from the model"). Edges match by their exact control points.
OrientStats orient_patches(std::vector<pool::PatchControlNet>& nets);

/// A cone bounding a set of directions.
struct NormalCone {
    double axis[3] = {0, 0, 1};
    double half_angle = 0.0;  ///< radians; >= pi/2 means "no useful cone"
    bool valid = false;
};

/// Cone containing every normal dQ/du x dQ/dv of the patch: the normal is a bidegree (5,5)
/// polynomial whose 36 Bernstein coefficients (sums of cross products of the derivative nets with
/// positive weights) span a convex cone containing all its values. Zero coefficients (collapsed
/// edges) are skipped.
NormalCone normal_cone(const pool::PatchControlNet& net);

/// Fills the stored cone fields of a node: octahedral axis, cosine widened by the encoding error.
void store_cone(const NormalCone& cone, pool::SubpatchNode& node);

/// seed 002, 5.1: the subpatch tree of one patch (level order, 2^(depth+1) - 1 nodes into `out`):
/// de Casteljau subdivision at 1/2, alternating u and v, u first; each node's box from its control
/// net, padded by `pad` (local units) before rounding to float.
void build_subpatch_tree(const pool::PatchControlNet& net, std::uint32_t depth, double pad,
                         pool::SubpatchNode* out);

struct BvhStats {
    std::uint32_t depth = 0;          ///< deepest level, root = 0
    std::uint32_t median_splits = 0;  ///< splits by median (coincident centroids or depth guard)
    double sah_cost = 0.0;            ///< sum over nodes of area / root area (1 per traversal or patch test)
};

/// seed 002, 5.1: BVH over the boxes by binned SAH on the centroids (Guenther et al. 2007), one
/// patch per leaf, stored depth first with skip offsets; boxes padded by `pad` and rounded
/// outwards. Depth is kept <= pool::k_max_patch_bvh_depth by falling back to median splits.
std::vector<pool::PatchBvhNode> build_patch_bvh(std::span<const Box> boxes, std::uint32_t bins, double pad,
                                                BvhStats* stats = nullptr);

struct BuildOptions {
    std::uint32_t depth = 6;  ///< subpatch tree depth (seed 002: 6)
    std::uint32_t bins = 16;  ///< SAH bins per axis
    bool orient = true;       ///< run orient_patches
};

/// Everything prt-patches writes.
struct PatchModel {
    pool::ModelInfo model_info{};
    pool::PatchInfo patch_info{};
    std::vector<pool::PatchControlNet> nets;  ///< local frame (world - origin)
    std::vector<pool::PatchBvhNode> bvh;
    std::vector<pool::SubpatchNode> nodes;
    OrientStats orient;
    BvhStats bvh_stats;
    std::uint32_t degenerate_patches = 0;  ///< patches with at least one collapsed edge
};

/// Builds the pool contents from world-space nets. `progress(done, total)` is called per patch.
PatchModel build_patch_model(std::vector<pool::PatchControlNet> nets, const BuildOptions& options,
                             const std::function<void(std::uint64_t, std::uint64_t)>& progress = {});

/// Adds model_info, patch_info, patch_control_points, patch_bvh, patch_subpatch_boxes.
void write_patch_sections(const PatchModel& model, pool::PoolWriter& writer);

}  // namespace prt::patches
