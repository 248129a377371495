// PointRT preprocess: the splat octree builder (thesis 2.2, 3.1, 3.2) shared by prt-octree, the
// tests and benchmarks. Produces exactly the pool sections octree_info, octree_nodes, leaf_info,
// splats (layout: formats/include/prt/formats/pool_layout.h).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "buffer.h"
#include "prt/core/disk_box.h"
#include "prt/formats/pool.h"

namespace prt::pre {

/// A node's cell: its level (root = 0) and integer coordinates (each < 2^level).
struct NodeCell {
    std::uint32_t level = 0;
    std::uint32_t cell[3] = {0, 0, 0};
};

struct OctreeParams {
    /// X of thesis 3.2: a leaf overlapped by more splats is split. 48 from measurement (1M-point
    /// sphere, k = 9 radii: X = 16 stores each splat 63 times and misses the 2 s build target,
    /// X = 32 10 times, X = 48 6.5 times in 1.4 s; scripts/bench-splat.sh).
    std::uint32_t max_leaf_splats = 48;
    std::uint32_t max_depth = 24;  ///< leaves at this level are never split
    bool replicate = true;         ///< store each splat in every leaf its disk overlaps
    // Added by prt-octree (issue 3); the fields above are the agreed interface.
    /// A node whose edge is shorter than min_cell_ratio x the mean radius of the splats overlapping
    /// it is not split: once cells are smaller than the disks, every cell keeps the disks that
    /// cover it (with k-NN radii, thesis 3.1, about k disks cover each surface point), so splitting
    /// no longer reduces the splats per leaf and only adds nodes. 0 disables the rule.
    float min_cell_ratio = 0.25f;
    unsigned threads = 0;  ///< worker threads; 0 = every hardware thread
    /// What is compared with X to decide a split. false (default, issue 3): every splat overlapping
    /// the node, replicas included, so X bounds the splats a ray tests per leaf. true: only the
    /// splats whose centre lies in the node (half-open cell), as in thesis 3.2/3.4 after [LMR07],
    /// where the tree is built on centres and replication does not change its structure.
    bool split_by_centres = false;
    /// Progress of the subtree phase, called from one thread with (splats done, splats in all
    /// subtrees); may be empty.
    std::function<void(std::uint64_t, std::uint64_t)> progress;
    /// Where the tree is built (issue 17): "cpu", "cuda" (level by level on device 0,
    /// prt/cuda/octree_cuda.h; throws when no device is usable) or "auto" (CUDA when a device is
    /// usable). The sections are the same byte for byte; the points' build records are made and
    /// Morton-sorted on the CPU either way.
    std::string backend = "cpu";
};

struct OctreeStats {
    std::uint32_t nodes = 0, depth = 0, filled_leaves = 0, empty_leaves = 0;
    std::uint64_t unique_splats = 0, stored_splats = 0;
    double replication_factor = 0;  ///< stored / unique
    double seconds = 0;
    // Added by prt-octree (issue 3):
    std::uint64_t skipped_splats = 0;  ///< points left out: radius not finite and positive, or no normal
    std::uint64_t max_leaf_count = 0;  ///< most splats in one leaf (> X where a stop rule held)
    std::uint64_t bytes = 0;           ///< payload bytes of the four octree sections
};

/// A built octree, ready to be added to a pool (add_octree_sections()).
struct SplatOctree {
    pool::OctreeInfo info{};
    std::vector<std::uint32_t> nodes;
    std::vector<std::uint32_t> leaf_info;  ///< filled_leaves + 1 entries
    std::vector<pool::Splat> splats;
};

/// Builds the octree over splats given in the model's local frame. Points whose radius is not
/// finite and positive are skipped (and counted in stats). Throws prt::Error if the node count
/// would exceed the 30-bit address range.
/// Details (issue 3): the root is a cube enclosing every disk (centre +- radius), enlarged by about
/// 1/1000. Node boxes are node_box() of the root, closed: a disk touching a face is stored on both
/// sides. Filled leaves are numbered, and their splats stored, in depth-first (Morton) order; in
/// each leaf the splats whose centre lies in the leaf come first, then the replicas. The output
/// does not depend on params.threads. Points with a zero or non-finite normal are skipped too.
SplatOctree build_octree(std::span<const pool::Float3> positions, std::span<const pool::Float3> normals,
                         std::span<const float> radii, const OctreeParams& params,
                         OctreeStats* stats = nullptr);

// ---- Added for the out-of-core brick build (issue 17) -------------------------------------------

/// Whether build_octree makes a splat of this point (thesis 3.1): a finite positive radius, a finite
/// position and a finite non-zero normal; the others are skipped.
bool octree_uses_point(const pool::Float3& position, const pool::Float3& normal, float radius);

/// build_octree's root cube, accumulated over points given in any number of batches (an out-of-core
/// build reads them in passes; merge() joins the bounds of parallel batches).
class RootBounds {
public:
    RootBounds();
    /// Adds a point; false (counted as skipped) when build_octree skips it: radius not finite and
    /// positive, a non-finite position, a zero or non-finite normal.
    bool add(const pool::Float3& position, const pool::Float3& normal, float radius);
    void merge(const RootBounds& other);
    std::uint64_t valid() const { return m_valid; }
    std::uint64_t skipped() const { return m_skipped; }
    /// The root cube (build_octree's details) with only root_min and root_size set. Throws
    /// prt::Error when no point was valid or float cannot enclose the model.
    pool::OctreeInfo root() const;

private:
    double m_lo[3], m_hi[3];
    std::uint64_t m_valid = 0, m_skipped = 0;
};

/// The subtree below node `cell` of the octree whose root cube is `root` (RootBounds::root()), as
/// build_octree would build it, given exactly the usable points whose disk overlaps that node (as
/// child_overlap_mask() decides it level by level from the root), in their input order. The
/// result's node 0 is `cell`; its leaves are numbered and its splats stored as in build_octree
/// (Splat::point is the index in these arrays); info holds the root cube and this subtree's counts
/// (depth: the deepest level in the whole octree's numbering). The caller checks that the
/// whole octree splits every ancestor of `cell` (octree_splits_node()).
SplatOctree build_octree_cell(std::span<const pool::Float3> positions, std::span<const pool::Float3> normals,
                              std::span<const float> radii, const pool::OctreeInfo& root, NodeCell cell,
                              const OctreeParams& params, OctreeStats* stats = nullptr);

/// A point as build_octree classifies it: the disk (centre, radius, unit normal rounded to float)
/// and its bounding box rounded outward. Prepared once (prepare_build_splat), it is classified at
/// any number of nodes (the out-of-core brick build walks each point down its partition twice).
using BuildSplat = core::BuildSplat;

/// The checks build_octree_cell makes of its parameters, its `points` and `cell` (throws
/// prt::Error), for a caller that builds the tree itself (cull_build.h, build_culled_cell, whose GPU
/// path makes the build records on the device).
void check_cell_build(const OctreeParams& params, std::size_t points, NodeCell cell);

/// The header and the statistics of a built octree (its nodes, leaf ranges and splats set), from
/// either builder: the root cube `root`, `unique` usable points, the deepest leaf's level, the empty
/// leaves and the largest leaf.
void describe_octree(SplatOctree& octree, const pool::OctreeInfo& root, const OctreeParams& params,
                     std::uint64_t unique, std::uint32_t depth, std::uint64_t empty, std::uint64_t max_leaf,
                     OctreeStats& stats);

/// The point's build record; false for a point build_octree skips (octree_uses_point()).
bool prepare_build_splat(const pool::Float3& position, const pool::Float3& normal, float radius,
                         BuildSplat& out);

/// A half-width h such that the box prepare_build_splat gives a usable point with centre coordinate
/// `c` and radius `radius` lies within [c - h, c + h] on that axis (the disk's extent is at most the
/// radius; the margin covers the box's outward rounding to float). A point whose cube c +- h reaches
/// no node's mid-plane goes to the child holding its centre (child_overlap_mask), so a caller can
/// place it without preparing it.
double build_splat_box_bound(double c, float radius);

/// A node's children's closed boxes (node_box()) and its mid-planes, for child_overlap_mask().
struct ChildBoxes {
    double mid[3];
    double lo[8][3];
    double hi[8][3];
};
ChildBoxes child_boxes(const pool::OctreeInfo& root, NodeCell node);

/// Bit c is set when build_octree puts the prepared point's splat in child c of the node whose child
/// boxes are `boxes` (replicate: its disk overlaps the child's closed box, thesis 3.4; otherwise the
/// child holding its centre).
std::uint8_t child_overlap_mask(const BuildSplat& splat, const ChildBoxes& boxes, bool replicate);

/// build_octree's split rule (thesis 3.2) for a node whose list holds `count` splats whose radii
/// sum to `radius_sum`, `centres` of them with their centre in the node's half-open cell (read
/// only with split_by_centres).
bool octree_splits_node(const OctreeParams& params, const pool::OctreeInfo& root, NodeCell node,
                        std::uint64_t count, double radius_sum, std::uint64_t centres);

/// The backend build_octree would use for `name` ("cpu", "cuda", "auto"). Throws prt::Error when
/// `name` is "cuda" and no CUDA device is usable (or the build has no CUDA), or `name` is unknown.
/// `why` gets a note when "auto" falls back to the CPU.
std::string resolve_octree_backend(const std::string& name, std::string* why = nullptr);

/// Adds (replacing) the four octree sections to a writer.
void add_octree_sections(SplatOctree octree, pool::PoolWriter& writer);

// ---- Added by prt-octree (issue 3) -------------------------------------------------------------

/// Throws prt::Error when an octree of this size cannot be encoded: more than 2^30 nodes (30-bit
/// child addresses), more than 2^30 filled leaves (30-bit leaf addresses) or more than 2^32 - 1
/// stored splats (32-bit leaf_info entries). The builder calls it while building, before the
/// memory for such a tree is allocated.
void check_octree_limits(std::uint64_t nodes, std::uint64_t filled_leaves, std::uint64_t stored_splats);

/// The box of the node at `level` with integer cell coordinates `cell` (each < 2^level), in the
/// root's frame: root_min + root_size * cell / 2^level in double precision (the product is exact for
/// level <= 29); neighbouring cells share their face coordinates exactly.
void node_box(const pool::OctreeInfo& info, std::uint32_t level, const std::uint32_t cell[3], double lo[3],
              double hi[3]);

}  // namespace prt::pre
