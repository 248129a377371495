// PointRT preprocess: probe-ray culling of replicated splats (thesis 3.4) and the hole-rate
// measurement that says what the culling cost.
//
// thesis 3.4: prt-octree stores every splat in every leaf its disk overlaps, so that a ray crossing
// a leaf finds the disks that cover the surface inside it; that costs 5-10x the input's memory. Most
// replicas are redundant: the leaf's own splats (those whose centre lies in it) already cover most
// of the surface inside it. Culling shoots probe rays through each filled leaf from many directions
// and keeps only the replicas some probe needs:
//
//   leaf L, box B, splats S(L) = centre splats C(L) + replicas R(L)
//   for each probe direction d (spread over a hemisphere, randomly rotated per leaf)
//     for each cell of a jittered G x G grid over the projection across d of the part of B that
//     L's disks reach
//       clip the probe line to L's closed cell (the renderer's cell planes): its range [t0, t1]
//       intersect every splat of L there (the renderer's intersect_splat); the line is two probe
//       rays, along d (disks facing -d) and along -d (disks facing d), each handled as below
//       thesis policy: no hit on C(L) -> keep every replica it hits
//       greedy policy: the nearest kept hit (C(L) + replicas kept so far) must lie inside the
//                      blending window of the nearest hit of all of S(L) (t_near + window * R_near);
//                      else keep the one replica hit inside that window closest to its centre
//       votes policy:  greedy, but the replica picked is the one that most probes not covered by
//                      C(L) hit inside their window (the thesis's per-splat hit counter as priority)
//
// "Greedy" is what the issue asks for ("better, the splats kept so far"): a replica is only kept
// for a probe that nothing kept so far serves, so overlapping replicas no longer all survive. The
// window test (rather than "any hit") means a probe also counts as unserved when a kept splat
// only hits it deeper than the surface it saw in the unculled leaf (the back of a thin part), so
// every probe sees the same surface, within the blending window, before and after culling.
//
// The device-callable half is prt/core/cull.h (PRT_HD, no STL, no allocation, no recursion): the CPU
// path (cull_build.cpp) and the CUDA path (runtime/cuda/src/cull.cu) run the same functions.
// Probe directions come from a table computed once on the host (no transcendental functions in
// the per-probe code), so the two backends shoot bit-identical probes when the CUDA code is
// compiled without FMA contraction (it is: --fmad=false).
#pragma once

#include <cstdint>
#include <functional>
#include <future>
#include <span>
#include <string>
#include <vector>

#include "octree_build.h"
#include "prt/core/cull.h"
#include "prt/core/octree.h"
#include "prt/core/splat.h"
#include "prt/formats/octree_sections.h"
#include "prt/formats/pool_layout.h"

namespace prt::pre {

// The device-callable half (probe rays, the per-leaf decision, the hole rays) lives in the core,
// prt/core/cull.h, for this CPU path and the CUDA backend alike.
using core::cull_leaf;
using core::CullCounters;
using core::CullLeaf;
using core::CullPolicy;
using core::CullView;
using core::HoleRay;
using core::HoleSample;
using core::k_cull_leaf_unknown;
using core::k_keep_centre;
using core::k_keep_none;
using core::k_keep_probe;
using core::KeepFlag;
using core::ProbeDirection;
using core::trace_hole_ray;

// ==== Host part ===================================================================================

/// The four octree sections of a pool (views; pool::PoolFile or a built SplatOctree owns them):
/// formats' typed view (prt/formats/octree_sections.h).
using OctreeSections = pool::SplatOctreeSections;

/// The core's view of octree sections (the renderer's OctreeView).
core::OctreeView octree_view(const OctreeSections& s);

struct CullParams {
    /// Probe line directions per leaf, spread evenly over a hemisphere; each line is probed both
    /// ways, so a leaf is probed from 2 x directions directions. Each leaf uses one of 64 random
    /// rotations of the set. Default (with grid) chosen by measurement: cull_build.cpp's header comment.
    std::uint32_t directions = 4;
    /// G: a G x G jittered grid of parallel probe lines per direction.
    std::uint32_t grid = 8;
    CullPolicy policy = CullPolicy::greedy;
    float window = 1.0f;  ///< blending window in radii (RenderParams::blend_window, the renderer's default)
    std::uint32_t seed = 1;
    unsigned threads = 0;  ///< CPU worker threads; 0 = every hardware thread
    /// "cpu", "cuda" or "auto" (cuda when this build has it and a device is usable).
    std::string backend = "auto";
    /// Progress, called from one thread with (leaves done, leaves); may be empty.
    std::function<void(std::uint64_t, std::uint64_t)> progress;
};

struct CullStats {
    std::string backend;  ///< the backend that ran ("cpu" or "cuda: DEVICE")
    std::uint64_t leaves = 0, leaves_with_replicas = 0;
    std::uint64_t unique_splats = 0;  ///< OctreeInfo::unique_splats
    std::uint64_t splats_before = 0, splats_after = 0;
    std::uint64_t centre_splats = 0;  ///< stored splats whose centre lies in their leaf (kept)
    std::uint64_t replicas_before = 0, replicas_kept = 0;
    std::uint64_t bytes_before = 0, bytes_after = 0;  ///< payload of leaf_info + splats
    CullCounters counters;
    double seconds = 0;  ///< culling (probing) time, without reading and writing pools
    double replication_before() const {
        return unique_splats ? double(splats_before) / double(unique_splats) : 0;
    }
    double replication_after() const {
        return unique_splats ? double(splats_after) / double(unique_splats) : 0;
    }
};

/// The culled octree: the node pool is unchanged (the input's); leaf_info and splats are rewritten,
/// octree_info gets the new splat count and k_octree_culled.
struct CulledOctree {
    pool::OctreeInfo info{};
    std::vector<std::uint32_t> leaf_info;
    std::vector<pool::Splat> splats;
};

/// Where the octree handed to culling sits in a whole one: its node 0 is the whole octree's node
/// `root` (an out-of-core build culls it cell by cell, issues 17 and 21: probes depend only on their
/// leaf's cell, core/cull.h leaf_hash, so the result is the whole octree's). The default is the
/// whole octree.
struct OctreePart {
    NodeCell root;
};

/// The filled leaves of an octree (level, cell, node word by leaf_info index), found by walking
/// the node pool from node 0, which is node `root` of the whole octree. Throws prt::Error on a
/// malformed tree.
std::vector<CullLeaf> collect_leaves(const OctreeSections& s, NodeCell root = {});

/// The probe direction table: `sets` random rotations of `directions` directions spread evenly over
/// a hemisphere (a Fibonacci spiral).
std::vector<ProbeDirection> make_probe_directions(std::uint32_t directions, std::uint32_t sets,
                                                  std::uint32_t seed);

/// Initial keep flags: k_keep_centre where the splat's centre lies in its leaf's closed box
/// (node_box(), the builder's test), k_keep_none elsewhere; every splat of an unknown leaf is kept.
std::vector<std::uint8_t> centre_flags(const OctreeSections& s, std::span<const CullLeaf> leaves);

/// The backend culling would use for `name` ("cpu", "cuda", "auto"). Throws prt::Error when `name`
/// is "cuda" and no CUDA device is usable (or the build has no CUDA), or `name` is unknown. `why`
/// gets a note when "auto" falls back to the CPU.
std::string resolve_cull_backend(const std::string& name, std::string* why = nullptr);

/// Creates the GPU's context on a thread of its own when `name` ("cuda" or "auto") may cull there
/// and a device is usable, so that prt-cull reads its input meanwhile (the context took a sizeable
/// share of prt-cull's time on 1M points); a ready future otherwise. Errors are left to the culling.
std::future<void> warm_up_cull_backend(const std::string& name);

/// When `backend` (resolved: "cpu" or "cuda") is "cuda": destroys the GPU's context on a thread of
/// its own (prt::cuda::release_device), so that prt-cull writes its output meanwhile instead of
/// paying the driver's teardown at exit; a ready future otherwise. Only after the last culling or
/// hole measurement: no GPU work may follow until the future is ready.
std::future<void> release_cull_backend(const std::string& backend);

/// Runs the per-leaf culling and returns the final keep flags (one per stored splat). Throws
/// prt::Error on invalid parameters or an octree that is not replicated.
std::vector<std::uint8_t> cull_keep_flags(const OctreeSections& s, const CullParams& params,
                                          CullStats* stats = nullptr, const OctreePart& part = {});

/// Culls an octree (thesis 3.4): cull_keep_flags(), then the kept splats in their leaf order.
CulledOctree cull_octree(const OctreeSections& s, const CullParams& params, CullStats* stats = nullptr,
                         const OctreePart& part = {});

/// One cell of the out-of-core brick build (issue 17), built and culled: build_octree_cell, then
/// cull_octree over OctreePart{cell}.
struct CulledCell {
    SplatOctree octree;        ///< the culled octree (info: k_octree_culled, the kept splats' count)
    std::uint64_t stored = 0;  ///< splats stored before culling
    bool on_device = false;    ///< built and culled on the GPU without the replicas coming down
    double build_seconds = 0;  ///< the octree (and the culling too, when on_device)
    double cull_seconds = 0;   ///< the culling, when not on_device
};

/// build_octree_cell then cull_octree over the cell, byte for byte; when both octree.backend and
/// culling.backend resolve to "cuda", in one pass on the GPU (prt/cuda/octree_cuda.h,
/// build_cull_octree_cuda): the tree is culled and compacted where it was built, so only the kept
/// splats come down (on the 500M room, 504M of 3.25G stored). Throws as the two steps do.
CulledCell build_culled_cell(std::span<const pool::Float3> positions, std::span<const pool::Float3> normals,
                             std::span<const float> radii, const pool::OctreeInfo& root, NodeCell cell,
                             const OctreeParams& octree, const CullParams& culling);

// ---- Hole rate -----------------------------------------------------------------------------------

/// Ray families of the hole measurement.
enum class HoleFamily : std::uint32_t {
    sphere = 0,   ///< from a random point of the bounding sphere towards a random point of the bounds
    reverse = 1,  ///< the same, traced as inside rays: they see back faces, as refracted rays do
    orbit = 2,    ///< pinhole views (64 x 64 jittered pixels, 40 degrees) from outside, looking at the centre
    inside = 3,  ///< pinhole views (64 x 64 jittered pixels, 90 degrees) from random points inside the bounds
};
inline constexpr std::uint32_t k_hole_families = 4;
const char* hole_family_name(HoleFamily f);

/// N rays, families in order: 40 % sphere, 10 % reverse, 25 % orbit, 25 % inside (views of up to
/// 4096 rays). `family_begin` gets the first index of each family (plus N at the end).
/// Deterministic in `seed`. The bounds are the splats' (centre +- radius).
std::vector<HoleRay> make_hole_rays(std::span<const pool::Splat> splats, std::uint64_t n, std::uint64_t seed,
                                    std::uint64_t family_begin[k_hole_families + 1]);

/// Tolerance of the hole measurement: a culled hit farther than this many mean splat radii from
/// the unculled one (along the ray) is on another surface: the ray went through a hole.
inline constexpr double k_hole_tolerance_radii = 3.0;

/// What one traced hole ray says (measure_holes counts these).
enum class HoleOutcome : std::uint32_t {
    no_hit,         ///< misses the unculled surface, and the culled one
    spurious,       ///< misses the unculled surface, hits the culled one (impossible: must not happen)
    on_surface,     ///< hits the unculled surface less than the tolerance from its origin: the ray
                    ///< starts inside the surface's band, where the measurement cannot tell a hole
    missed,         ///< hits the unculled surface, misses the culled one: a hole
    wrong_surface,  ///< hits the culled surface more than the tolerance away: a hole
    same,           ///< hits both within the tolerance: no hole
};

/// The outcome of one ray, `tolerance` being k_hole_tolerance_radii mean splat radii. A ray whose
/// unculled hit lies within the tolerance of its origin is not counted (on_surface): a camera of
/// the inside family may sit inside the splat layer itself (the Stanford bunny, hole seed 7: one
/// 64 x 64 view 8e-6 from a disk, 0.01 splat radii, gave 2133 of the measurement's 2740 holes, so
/// the rate jumped between 0.15 and 1.53 % with the culling seed).
HoleOutcome classify_hole_sample(const HoleSample& s, double tolerance);

struct HoleCounts {
    std::uint64_t rays = 0;
    std::uint64_t on_surface = 0;  ///< rays not counted: their unculled hit is within the tolerance
    std::uint64_t hit_full = 0;    ///< rays that hit the unculled surface (on_surface ones excluded)
    std::uint64_t missed = 0;      ///< of those, rays that miss the culled surface entirely
    std::uint64_t wrong_surface =
        0;                        ///< of those, rays whose culled hit is k_hole_tolerance_radii away or more
    std::uint64_t spurious = 0;   ///< miss the unculled surface, hit the culled one (impossible: must be 0)
    double normal_error_sum = 0;  ///< degrees between the blended normals, over rays that are no holes
    std::uint64_t normal_count = 0;
    std::uint64_t holes() const { return missed + wrong_surface; }
    /// Rays that hit the unculled surface but miss the culled one there, over rays that hit the
    /// unculled surface.
    double hole_rate() const { return hit_full ? double(holes()) / double(hit_full) : 0.0; }
    double miss_rate() const { return hit_full ? double(missed) / double(hit_full) : 0.0; }
    double mean_normal_error() const { return normal_count ? normal_error_sum / double(normal_count) : 0.0; }
    HoleCounts& operator+=(const HoleCounts& o);
};

struct HoleStats {
    HoleCounts total;
    HoleCounts family[k_hole_families];
    std::string backend;
    double seconds = 0;
};

struct HoleParams {
    std::uint64_t rays = 1000000;
    std::uint64_t seed = 7;
    float window = 1.0f;  ///< blending window (RenderParams::blend_window)
    unsigned threads = 0;
    std::string backend = "auto";
};

/// Shoots HoleParams::rays rays (make_hole_rays) at both octrees and counts rays that hit the
/// unculled surface but miss the culled one. Both octrees must share their node pool and frame.
HoleStats measure_holes(const OctreeSections& full, const OctreeSections& culled, const HoleParams& params);

}  // namespace prt::pre
