// PointRT preprocess: the kd-tree over the MLS surface of Wald & Seidel 2005 ("WS05", 3.4), shared
// by prt-mls, the tests and the benchmarks. Host only.
//
// Build, in four passes:
//   1. SAH (WS05 3.4, eq. 3) over each splat's support box [p - R, p + R], exact sweep over the
//      box boundaries, optionally with E(n) lowering the cost of small cells (3.4.2); every cell
//      references the splats whose support ball overlaps it (exact sphere-box test);
//   2. cell shrinking (3.4.1) of every leaf, slice by slice, proven with interval arithmetic
//      instead of WS05's random sampling (the paper names it the better way): a slice is cut off
//      only when F provably has no zero with W > 0 in it, so shrinking never loses surface;
//   3. post-collapse (3.4.3) of splits whose two children are both empty;
//   4. flattening into the pool layout (prt/formats/mls_layout.h);
//   5. a BVH over the non-empty leaves for the ray walk (mls_bvh.h; BuildOptions::bvh).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "prt/formats/mls_layout.h"
#include "prt/formats/pool_layout.h"

namespace prt::mls {

/// Default support factor: support radius R_i = factor x splat radius r_i (prt-radii's k-th
/// nearest neighbour distance, k = 9 by default). Measured (scripts/bench-mls.sh): with k = 9 radii
/// a factor of 1 already covers the sphere, the sampled bunny and the kitten without holes; 1.5
/// and 2 cost 2x and 4x the splats per cell (half and a quarter of the rays/s) and smooth more
/// (the MLS sphere lies further inside the true one). Issue 15 measured 0.8 better on real scans
/// (prt-fidelity: the ten bunny scans' false hits 0.28 % -> 0.18 %, the armadillo's holes
/// 1.5 % -> 0.7 %: a smaller support smooths less, so silhouettes and thin parts shrink less)
/// while the laser-scan simulations keep holes at or below 0.1 % (scripts/suite/RESULTS.md).
inline constexpr float k_default_support_factor = 0.8f;

/// Build settings (prt-mls options, with the same defaults).
struct BuildOptions {
    float support_factor = k_default_support_factor;
    std::uint32_t samples = 4;       ///< WS05 3.2.2's k the tree is built for (recorded in MlsInfo)
    /// C_trav of WS05 eq. 3. 3 since 2026-12-03 (was 1): fewer, larger cells, which the finer
    /// shrinking below makes as tight; the GPU walk pays per node (preprocess/mls/README.md).
    float cost_traversal = 3.0f;
    float cost_intersection = 1.5f;  ///< C_isec of WS05 eq. 3, per referenced splat
    /// WS05 3.4.2: C_cell(n) = C_isec n E(n), see encourage_factor(). Off since 2026-12-03: with
    /// finer shrinking and the samples per support radius (core::MlsParams) the smaller cells it
    /// makes no longer buy accuracy, and cost the GPU 1.6x on prt-synth's room.
    bool encourage = false;
    /// WS05 3.4.2's E(n) reaches 1 at n = 21 refs, tuned for Wu-Kobbelt radii (little overlap);
    /// E(n) = min(1, (95 + 5 n 21 / limit) / 200) stretches it to cells of up to `limit` refs.
    /// Default 40: measured on the sampled bunny, 19% fewer splats per ray and 6% fewer cycles
    /// than 21 (kNN radii overlap more than WS05's, so cells rarely have fewer than 21 refs).
    float encourage_limit = 40.0f;
    bool shrink = true;               ///< WS05 3.4.1: shrink leaves to the surface
    /// K slices per axis (WS05 uses 7-13; 8 until 2026-12-03): finer slices cut the cells closer
    /// to the surface band, so fewer cells and splats meet a ray (prt-synth's room: 2.6x on the GPU
    /// with the settings above, preprocess/mls/README.md).
    std::uint32_t shrink_slices = 128;
    std::uint32_t shrink_axes = 3;  ///< 1: the dominant normal axis only (WS05); 3: all axes, dominant first
    /// Interval subdivision levels inside a slice: a slice is kept when a sub-box this many
    /// halvings down still cannot be proven free of the surface.
    std::uint32_t shrink_depth = 6;
    bool collapse = true;          ///< WS05 3.4.3: merge splits whose two children are empty
    /// Pass 5 (not in WS05): a BVH over the non-empty leaves for the ray walk (mls_bvh.h). false:
    /// the pool holds the kd-tree alone and rays walk it (as before 2026-12-03).
    bool bvh = true;
    std::uint32_t max_depth = 48;  ///< SAH levels; shrinking adds at most 6 (pool::k_max_mls_depth)
    unsigned threads = 0;          ///< 0 = every hardware thread
};

/// Throws prt::Error naming the first invalid option.
void validate(const BuildOptions& options);

/// Facts about a build, for the tool's report and the benchmarks.
struct BuildStats {
    std::uint64_t points = 0;   ///< input points
    std::uint64_t skipped = 0;  ///< points without a usable radius/normal/position
    std::uint64_t splats = 0;
    std::uint64_t nodes = 0, leaves = 0, empty_leaves = 0;
    std::uint64_t refs = 0;
    std::uint32_t depth = 0;
    std::uint64_t sah_leaves = 0;     ///< leaves after pass 1
    double sah_cost = 0;              ///< SAH cost of the tree after pass 1 (relative to the root)
    std::uint64_t shrunk_leaves = 0;  ///< leaves shrunk along at least one axis
    std::uint64_t culled_leaves = 0;  ///< leaves found entirely free of the surface
    std::uint64_t shrink_splits = 0;  ///< split nodes inserted by shrinking
    std::uint64_t refs_removed = 0;   ///< refs dropped because the shrunk cell no longer overlaps the splat
    double volume_before = 0,
           volume_after = 0;           ///< total volume of non-empty leaves before / after shrinking
    std::uint64_t interval_boxes = 0;  ///< boxes classified by interval arithmetic
    std::uint64_t collapsed = 0;       ///< split nodes removed by post-collapse
    std::uint64_t bvh_nodes = 0;       ///< pass 5: BVH nodes over the non-empty leaves (0: no BVH)
    std::uint32_t bvh_depth = 0;
    double seconds_sah = 0, seconds_shrink = 0, seconds_bvh = 0, seconds_total = 0;
    double mean_refs_per_leaf() const;  ///< over non-empty leaves
};

/// The built surface in pool layout.
struct MlsModel {
    pool::MlsInfo info{};
    std::vector<pool::MlsNode> nodes;
    std::vector<std::uint32_t> refs;
    std::vector<pool::MlsSplat> splats;
    std::vector<pool::MlsBvhNode> bvh_nodes;  ///< pass 5 (BuildOptions::bvh); empty: none
    std::vector<pool::MlsBvhLeaf> bvh_leaves;
    BuildStats stats;
};

/// Builds the kd-tree over the splats (positions, normals, radii per point, local frame). Points
/// with a radius that is not finite and > 0, a non-finite position or a zero / non-finite normal
/// are skipped (counted in stats.skipped). Throws prt::Error on invalid options, mismatched
/// sizes, no usable splat, or a tree that does not fit the layout. `progress(done, total)` is
/// called from the calling thread (leaves shrunk).
MlsModel build_mls(std::span<const pool::Float3> positions, std::span<const pool::Float3> normals,
                   std::span<const float> radii, const BuildOptions& options,
                   const std::function<void(std::uint64_t, std::uint64_t)>& progress = {});

/// WS05 3.4.2: E(n) = min(1, (95 + 5 n') / 200) with n' = n 21 / limit (limit 21: the paper's E).
double encourage_factor(std::uint64_t n, double limit = 21.0);

// ---- Interval classification (WS05 3.4.1, exposed for the tests) ---------------------------------

/// An axis-aligned box, local frame.
struct Box {
    double lo[3], hi[3];
};

/// Whether splat `s`'s support ball reaches into `b` (|p - b| < R, with a relative margin of 1e-5
/// on R^2 so float rounding in the core never sums a splat its cell does not reference).
bool support_overlaps(const pool::MlsSplat& s, const Box& b);

/// Conservative test: false only when F provably has no zero with W > 0 in the closed box `b`
/// (interval bounds of F, and f as a convex combination of (x - p_i) . n_j, refined by halving
/// the box up to `depth` levels). `candidates` must hold every splat whose support reaches `b`.
/// `boxes`, if set, counts the boxes classified.
bool may_contain_surface(const Box& b, std::span<const pool::MlsSplat> splats,
                         std::span<const std::uint32_t> candidates, std::uint32_t depth,
                         std::uint64_t* boxes = nullptr);

}  // namespace prt::mls
