// PointRT preprocess: the Implicit Surface Octree builder (thesis ch. 4), shared by prt-iso, the
// tests and the benchmarks. Host only. Produces the pool sections of prt/formats/iso_layout.h.
//
// Build, in order:
//   1. radii of influence r_i: the pool's radii section (prt-radii, thesis 3.1) or prt-iso's own
//      k-nearest-neighbour distance (same definition, same outlier clamp); the Gaussian of eq. 4.1
//      uses sigma_i = smoothing x r_i (fig. 4.12: the smoothing factor scales the radius);
//   2. the octree over the point positions only (thesis 4.3.1): a node holding points is split
//      while it is above min_level, or above max_level is not reached and it holds more than
//      max_points points (thesis 4.6: the leaf levels are the user's, independent of the count);
//      leaves with points are *active*;
//   3. passive leaves (thesis 4.3.1): empty leaves that the disk of a point's influence
//      (centre p_i, normal n_i, radius max(r_i, sigma_i)) touches, found by the exact disk/box
//      test while descending the tree from the smallest node holding the disk; passive leaves
//      above min_level are split down to it;
//   4. 2:1 balance (thesis 4.5.1): a filled leaf next to (sharing a face, edge or corner with) a
//      filled leaf more than one level finer is split, finest levels first, until none is;
//   5. the isovalue f(Q) = (Q - p(Q)) . n(Q), the normalized weighted normal n(Q) and the weighted
//      color at every distinct corner Q of every filled leaf (thesis 4.2-4.3, eq. 4.1-4.3);
//   5b. surface closure: where a filled leaf's face has corners of both signs, its trilinear
//      surface crosses that face, so the leaves behind it are filled too (split down from coarser
//      empty leaves; a coarser filled leaf without a sign change is split), their corners
//      evaluated, and so on until no face leads to an empty leaf; 2:1 balance is kept. This
//      catches what the disks of step 3 miss (noisy scans, where the smoothed surface leaves the
//      disks; coarse levels of detail, where disks are small against leaves);
//   5c. data support (issue 15): a corner whose projection onto its local plane lies farther than
//      data_reach x r_i from every point i is unsupported (and so is a corner no point's support
//      reaches); the closure does not grow from leaves with such a corner, and step 6 empties them:
//      no sheets past a scan's edges or across holes wider than about 2 data_reach r;
//   6. filled leaves whose 8 corners share one sign hold no surface (trilinear interpolation is
//      a convex combination of the corners) and become empty leaves; subtrees without a filled
//      leaf collapse into one empty leaf;
//   7. the node pool (breadth first) and the leaf arrays (depth-first order), quantized to one
//      byte per component (thesis 4.4, 56 bytes per leaf) and/or in floats.
//
// Which points count at a corner: the thesis searches within "the maximum radius of influence of
// any point in that leaf" (4.3). Here every point counts whose own support reaches the corner
// (|Q - p_i| <= support x sigma_i), so a corner has one value whichever of its leaves asks, and
// leaves sharing a corner agree there (the continuity thesis 4.5 relies on); with one_side (the
// default, issue 15) only those on the heavier side, split by their normal against the corner's
// heaviest point's, so the two sides of a thin part do not cancel. A corner no point's support reaches
// (coarse levels of detail, thesis 4.6) is evaluated from the points within d_min + support x sigma_max of it
// (d_min: the nearest point's distance), where the untruncated Gaussians of eq. 4.1 put all but a negligible
// part of their weight, with the weights scaled in log space so that they cannot underflow.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "prt/formats/iso_layout.h"
#include "prt/formats/pool_layout.h"

namespace prt::iso {

/// Where the radius of influence r_i of each point comes from.
enum class RadiusSource : std::uint32_t {
    automatic,  ///< the radii section when given, else k-NN
    radii,      ///< the radii section (prt-radii); an error when absent
    knn,        ///< distance to the k-th nearest other point, computed here
};
/// "auto", "radii", "knn".
const char* radius_source_name(RadiusSource s);
/// The source named `name`; throws prt::Error for an unknown name.
RadiusSource parse_radius_source(const std::string& name);

/// Which leaf arrays to write.
enum class Storage : std::uint32_t {
    q8,    ///< quantized, 56 bytes per leaf (thesis 4.4)
    f32,   ///< floats, 160 bytes per leaf
    both,  ///< both arrays (the tracer picks with IsoView::use_q8)
};
const char* storage_name(Storage s);
Storage parse_storage(const std::string& name);

/// Build settings (prt-iso options, with the same defaults).
struct BuildOptions {
    std::uint32_t min_level = 0;   ///< thesis 4.6: no filled leaf above this level
    std::uint32_t max_level = 10;  ///< thesis 4.6: no leaf below this level (<= pool::k_max_iso_level)
    /// A node holding more points than this is split (until max_level). With 2, leaves are about
    /// as many as points on scanned surfaces (the thesis's David: 1.09 M leaves for 1.0 M points).
    std::uint32_t max_points = 2;
    /// fig. 4.12: sigma_i = smoothing x r_i (< 1 sharper, > 1 smoother). 0.5 by measurement (issue
    /// 15, prt-fidelity): 1 shrinks curved parts inward (holes along silhouettes: the armadillo 6 %,
    /// a single bunny scan 0.8 %); 0.5 halves that with no new false hits on the scans.
    float smoothing = 0.5f;
    float support = 3.0f;  ///< a point counts at a corner within support x sigma_i (in sigmas)
    RadiusSource radius = RadiusSource::automatic;
    std::uint32_t knn = 9;       ///< k of the k-NN radius (thesis 3.1: about 9 neighbours)
    float knn_clamp = 3.0f;      ///< k-NN radii above this x their median are clamped (0 = off)
    bool passive = true;         ///< thesis 4.3.1: fill passive leaves
    bool balance = true;         ///< thesis 4.5.1: 2:1 level balance of filled leaves
    bool closure = true;         ///< step 5b: fill the leaves the surface leads into
    bool drop_uncrossed = true;  ///< step 6 (leaves without a sign change become empty)
    /// Step 5c (issue 15, no surface where there is no data): a corner holds surface only when its
    /// projection onto the local plane (p(Q), n(Q) of eq. 4.2) lies within data_reach x r_i of some
    /// point i; a leaf with another corner is empty. Gaps in the data wider than about
    /// 2 data_reach r (r: the points' radius, the k-th neighbour distance) are not bridged and no
    /// sheet grows past a scan's edge. 0 turns it off (the thesis's behaviour).
    float data_reach = 1.0f;
    /// Issue 15, thin parts (ears, fingers, a table top's edge): at a corner the points are split by
    /// their normal against the heaviest point's (within 90 degrees or not) and only the side of
    /// larger total weight counts, so the two sides of a part thinner than the Gaussian's reach do not cancel
    /// into nothing. false: every point within its support counts (thesis eq. 4.1-4.3 as written).
    bool one_side = true;
    Storage storage = Storage::q8;
    unsigned threads = 0;  ///< worker threads; 0 = every hardware thread
    /// Testing: the surface closure's parallel pass only locates the cells beyond crossed faces
    /// and leaves every decision to its serial pass (the tree must be the same).
    bool closure_serial_only = false;
};

/// Throws prt::Error naming the first invalid option.
void validate(const BuildOptions& options);

/// Facts about a build, for the tool's report and the benchmarks.
struct BuildStats {
    std::uint64_t points = 0;                ///< input points
    std::uint64_t skipped = 0;               ///< points without a usable position, normal or radius
    std::uint64_t radii_clamped = 0;         ///< k-NN radii lowered to the clamp
    double radius_median = 0;                ///< median r_i (local units)
    std::uint64_t active_leaves = 0;         ///< filled leaves with points (before step 6)
    std::uint64_t passive_leaves = 0;        ///< filled leaves without points (before step 6)
    std::uint64_t balance_splits = 0;        ///< leaves split by the 2:1 balance
    std::uint64_t min_level_splits = 0;      ///< passive leaves split down to min_level
    std::uint64_t corners = 0;               ///< distinct corners evaluated
    std::uint64_t corner_slots = 0;          ///< 8 x filled leaves: corner values stored
    std::uint64_t far_corners = 0;           ///< corners no point's support reached (see the header)
    std::uint64_t mean_neighbours_x100 = 0;  ///< 100 x mean points counted per corner
    std::uint64_t closure_leaves = 0;        ///< leaves filled by the surface closure (step 5b)
    std::uint64_t uncrossed_leaves = 0;      ///< filled leaves without a sign change (emptied in step 6)
    std::uint64_t unsupported_corners = 0;   ///< corners whose projection lies away from the data (5c)
    std::uint64_t unsupported_leaves = 0;    ///< filled leaves emptied for such a corner (5c, step 6)
    std::uint64_t leaves = 0;                ///< filled leaves written
    std::uint64_t nodes = 0;                 ///< node words written
    std::uint32_t depth = 0;                 ///< deepest filled leaf
    std::uint64_t leaves_per_level[pool::k_max_iso_level + 1] = {};
    std::uint64_t bytes = 0;  ///< payload bytes of the ISO sections
    double seconds_radii = 0, seconds_tree = 0, seconds_passive = 0, seconds_balance = 0;
    double seconds_corners = 0, seconds_closure = 0, seconds_encode = 0, seconds_total = 0;
};

/// The built ISO in pool layout.
struct IsoModel {
    pool::IsoInfo info{};
    std::vector<std::uint32_t> nodes;
    std::vector<pool::IsoLeafQ8> leaves_q8;    ///< empty unless Storage::q8 or both
    std::vector<pool::IsoLeafF32> leaves_f32;  ///< empty unless Storage::f32 or both
    BuildStats stats;
};

/// The input points, model local frame. `radii` and `colors` may be empty (radii then come from
/// k-NN, corner colors are 255); otherwise they have positions.size() elements.
struct BuildInput {
    std::span<const pool::Float3> positions;
    std::span<const pool::Float3> normals;
    std::span<const float> radii;
    std::span<const pool::Rgba8> colors;
};

/// Builds the ISO. Points with a non-finite position, a zero or non-finite normal, or a radius
/// that is not finite and > 0 are skipped (stats.skipped). Throws prt::Error on invalid options,
/// mismatched sizes, no usable point, or a tree too large for 30-bit node addresses.
/// `progress(stage, done, total)` is called from the calling thread.
IsoModel build_iso(const BuildInput& input, const BuildOptions& options,
                   const std::function<void(const char*, std::uint64_t, std::uint64_t)>& progress = {});

/// The integer cell of a filled leaf (for tests and tools): its level and coordinates there.
struct LeafCell {
    std::uint32_t level = 0;
    std::uint32_t x = 0, y = 0, z = 0;
};
/// The cell of every filled leaf, by leaf index, from a node pool (breadth first, children in
/// Morton order); nodes must form a valid tree (load_iso_view checks).
std::vector<LeafCell> leaf_cells(std::span<const std::uint32_t> nodes, std::uint32_t leaf_count);

/// The corner Q (local frame, double) of a leaf cell: root_min + root_size (cell + offset) / 2^level,
/// corner c = x | y << 1 | z << 2 as in iso_layout.h.
void corner_position(const pool::IsoInfo& info, const LeafCell& cell, int corner, double q[3]);

}  // namespace prt::iso
