// PointRT preprocess: the BVH over the MLS kd-tree's non-empty leaves (prt-mls's pass 5; layout in
// prt/formats/mls_layout.h, walked by prt/core/mls.h). Host only.
//
// Why: the kd-tree of WS05 3.4 cuts empty space into empty leaves, and a ray crossing a room's empty
// inside walks them all (prt-synth's room from prt-bench's camera: 274 kd nodes and 54 leaves a
// primary ray, 1.1 of them sampled). A BVH over the non-empty leaves, each boxed by its cell cut to
// its splats' support balls, skips that space (26 node visits) and samples the same cells over the
// same intervals, so the hits are the kd walk's.
#pragma once

#include <cstdint>

#include "mls_build.h"

namespace prt::mls {

/// Builds model.bvh_nodes / bvh_leaves and model.info.bvh_depth from the flattened kd-tree: one
/// leaf per non-empty kd leaf, binned SAH over the leaves' boxes (the 16-bin sweep of Wald 2007,
/// "On fast construction of SAH-based bounding volume hierarchies"), halves by count below level 32
/// so the depth stays within pool::k_max_mls_bvh_depth. Fewer than two non-empty leaves: no BVH
/// (the arrays stay empty, the kd walk is used). Records bvh_nodes, bvh_depth and seconds_bvh.
void build_mls_bvh(MlsModel& model);

}  // namespace prt::mls
