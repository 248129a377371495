// PointRT core: the splat octree as seen by a ray (thesis 2.2).
//
// The pool stores the octree as 32-bit node words (pool_layout.h): node 0 is the root, the 8
// children of an internal node are contiguous in Morton order c = x | y<<1 | z<<2. A ray walks the
// leaves it crosses, front to back:
//
//   thesis 2.2.1: find the leaf holding the current point, test its splats, move to the point
//                 where the ray leaves that leaf, repeat until the ray leaves the root;
//   thesis 2.2.2: each lookup descends top-down, in the root's normalized coordinates, picking
//                 the child from the next bit of the point's coordinates. The walk keeps the
//                 path of node indices to the current leaf and starts the next descent at the
//                 deepest node that path shares with the next cell (the level above the highest
//                 fixed-point bit that changed) instead of at the root: the same leaf, with fewer
//                 dependent memory reads (measured: see runtime/README.md).
//   addition (macro-regions, Devillers 1989): an empty leaf may carry a box of free cells around
//                 it (MacroRegion; three, each grown along one axis first, the ray's major axis
//                 picking one); the walk then leaves it through that box's exit face, passing
//                 in one step the empty leaves it would have visited one by one.
//
// Robustness (DESIGN.md, numerical robustness): the thesis nudges the exit point by a small
// epsilon; here there is none. The current point is held in 30-bit fixed point per axis
// (k_fixed_bits), the exit axis is the nearest of the three axis-plane crossings, and the
// neighbour is entered by integer cell arithmetic: the exit-axis coordinate is set to the first
// (or last) fixed-point value of the neighbouring cell, the other two are the ray's float position
// at the exit clamped into the current cell and never moved backwards along the ray. Every step
// therefore moves the point by at least one fixed-point unit along some axis, strictly forward,
// whatever the model's scale, offset or depth, and for rays that graze faces, edges and corners.
// Ray parameters t (used only to order hits) come from floats; correctness of the walk does not.
// The number of steps per ray is bounded (RenderParams::max_steps) and truncation is counted.
#pragma once

#include <cstdint>

#include "prt/core/math.h"
#include "prt/core/ray.h"
#include "prt/formats/pool_layout.h"

namespace prt::core {

#ifndef PRT_DEVICE_WALK_RCP
/// 1: device code, too, crosses cell planes by multiplying with the walk's 1 / d (walk_step_out), as
/// the host always does; 0 (the default): it divides (CUDA's fast division). Measured on an H200
/// (prt-bench, culled 1M room and sphere): 1 is 4-6 % slower for the float kernel's shadow rays and
/// 0.5-1 % for primary rays (preprocess/bench/results/h200-2026-12-01-issue19-cpu).
#define PRT_DEVICE_WALK_RCP 0
#endif
#define PRT_WALK_RCP (!PRT_DEVICE_CODE || PRT_DEVICE_WALK_RCP)

/// Bits of the fixed-point coordinates: the deepest level the walk can resolve. Pool positions are
/// floats (24-bit mantissa), so deeper trees carry no extra information.
inline constexpr std::uint32_t k_fixed_bits = 30;
inline constexpr std::uint32_t k_fixed_one = 1u << k_fixed_bits;
inline constexpr std::uint32_t k_fixed_max = k_fixed_one - 1;

/// Bounds on the splats of one filled leaf, derived from the pool on the host when a scene is
/// loaded (rt::build_leaf_bounds) so that a ray can pass a leaf without reading its splats
/// (splat.h, leaf_may_hit), with a copy of the leaf's splat range, so that one 32-byte read (two
/// 16-byte loads, one memory sector) gives a visited leaf everything but its splats. Not a pool
/// section.
///   normal cone: every splat normal n of the leaf (unit) makes an angle of at most theta with
///                `axis`; `sin_theta` is sin(theta) plus a rounding margin, or 2 when the normals
///                do not fit in a cone narrower than a half-space (the cone test never passes).
///   slab:        every point of every disk of the leaf lies in lo <= dot(axis, p) <= hi (local
///                frame, widened by a rounding margin); lo > hi when no splat of the leaf can be hit.
struct alignas(16) LeafBounds {
    float axis_x, axis_y, axis_z;  ///< 0: unit cone axis, also the slab normal
    float sin_theta;               ///< 12
    float lo, hi;                  ///< 16, 20: the slab
    std::uint32_t begin, end;      ///< 24, 28: the leaf's splats [begin, end) (leaf_info, clamped)
};
static_assert(sizeof(LeafBounds) == 32);

/// LeafBounds in 16 bytes, for the leaves of bricks (issue 17: 32-byte bounds were a third of a
/// streamed brick's block on the GPU, so half as many bytes fit a sixth more bricks in a budget).
/// The same normal cone and slab, about an axis quantized to integers (each component round(32767
/// a), |axis| about 32767) and built about that integer axis exactly as the test reads it, so
/// quantizing loses no conservativeness, only a little tightness:
///   cone:  dot(axis, d) / |d| >= sin_code passes the leaf (outside rays; inside rays negate), i.e.
///          sin(theta) + margin scaled by |axis| and rounded up; 65535 never passes (> |axis|);
///   slab:  lo <= dot(axis, p) <= hi for every point of every disk, in the same scale.
/// No splat range: a leaf that may hold a hit reads it from the brick's leaf_info (bricks.h).
struct alignas(16) BrickLeafBounds {
    std::int16_t axis_x, axis_y, axis_z;  ///< 0: the cone axis and slab normal, |axis| ~ 32767
    std::uint16_t sin_code;               ///< 6: the cone's threshold on dot(axis, d) / |d|
    float lo, hi;                         ///< 8, 12: the slab; lo > hi when no splat can be hit
};
static_assert(sizeof(BrickLeafBounds) == 16);
inline constexpr float k_brick_axis_scale = 32767.0f;
inline constexpr std::uint16_t k_brick_cone_never = 0xffffu;

/// The axis-aligned box, in normalized root coordinates (the walk's), of every hittable disk stored
/// in the leaves below one internal node (rt::build_node_boxes); lo > hi when there is none.
struct alignas(8) NodeBox {
    float lo[3], hi[3];
};
static_assert(sizeof(NodeBox) == 24);

/// The macro-region of an empty leaf (Devillers 1989, "The macro-regions: an efficient space
/// subdivision structure for ray tracing"; an addition to thesis 2.2.1): a box of cells at the
/// leaf's level around the leaf's cell, `below[a]` cells below it and `above[a]` above it on axis a,
/// in which no leaf holds a disk the ray can hit (empty leaves, and filled ones with no splat). The
/// walk leaves an empty leaf through its macro-region's exit face instead of its cell's: it passes
/// only leaves it would have found nothing in, so the hits are the same. All zero: the cell alone.
struct alignas(8) MacroRegion {
    std::uint8_t below[3], above[3];
    std::uint16_t unused;
};
static_assert(sizeof(MacroRegion) == 8);

/// Macro-regions come k_region_axes to an empty leaf, region a grown along axis a first (as far as
/// it goes, then every way): a ray leaves the leaf through the region of its major axis
/// (region_axis), the box longest along its path. One box grown every way in turn: the culled room
/// (prt-bench's, bench_room.json) 8.3 region steps per primary ray, the 10M sphere's ISO 6.4 (7.6
/// and 6.4 with the halving steps of rt::build_macro_regions); one per axis, halving, 5.7 and 5.0
/// (CPU counts, 256^2; preprocess/bench/results/h100-2026-12-06-issue19-region-axes).
inline constexpr std::uint32_t k_region_axes = 3;

/// The axis along which `d` is longest (ties to the lower axis): which of an empty leaf's
/// k_region_axes regions a ray of direction d leaves it through.
PRT_HD PRT_INLINE std::uint32_t region_axis(Vec3 d) {
    const float x = fabsf(d.x), y = fabsf(d.y), z = fabsf(d.z);
    return x >= y ? (x >= z ? 0u : 2u) : (y >= z ? 1u : 2u);
}

/// A non-owning view of a model's octree sections (pool section types 16-19).
struct OctreeView {
    const std::uint32_t* nodes = nullptr;  ///< octree_nodes, node_count words
    std::uint32_t node_count = 0;
    const std::uint32_t* leaf_info = nullptr;  ///< filled_leaves + 1 begin indices into splats
    std::uint32_t filled_leaves = 0;
    const pool::Splat* splats = nullptr;  ///< leaf-contiguous splats
    std::uint32_t splat_count = 0;
    Vec3 root_min{0, 0, 0};  ///< root cube corner, model local frame
    float root_size = 1.0f;  ///< root cube edge
    float inv_root_size = 1.0f;
    std::uint32_t flags = 0;  ///< pool::OctreeFlags
    /// One LeafBounds per filled leaf (same index as leaf_info), or null: leaves are then never
    /// skipped without testing their splats.
    const LeafBounds* leaf_bounds = nullptr;
    /// One NodeBox per internal node, indexed by its children block ((address - 1) / 8), or null:
    /// walk_next then descends into every internal node the ray's cell path meets.
    const NodeBox* node_boxes = nullptr;
    /// Set whenever node_boxes is: per internal node (same index), bit c set when child c's box is
    /// worth a test (rt::build_node_boxes: an internal child whose box a line through its cell
    /// meets with a chance under k_node_box_test_below).
    const std::uint8_t* node_box_mask = nullptr;
    /// The empty leaves' macro-regions (rt::build_macro_regions), or null: the walk then steps out
    /// of each empty leaf through its own cell. With them, `nodes` is the renderer's copy of the node
    /// pool in which an empty leaf's address bits a (0 in the pool) index this table: its regions
    /// are entries [a k_region_axes, (a + 1) k_region_axes), a = 0 for none.
    const MacroRegion* macro_regions = nullptr;
    std::uint32_t macro_region_count = 0;  ///< entries of macro_regions (the first k_region_axes unused)
};

/// The view over splat-octree arrays (a pool's sections, checked when the pool was opened and read
/// by pool::splat_octree, or an octree in memory), counts and root cube from `info`; no leaf bounds.
/// Host only.
inline OctreeView make_octree_view(const pool::OctreeInfo& info, const std::uint32_t* nodes,
                                   const std::uint32_t* leaf_info, const pool::Splat* splats) {
    OctreeView v;
    v.nodes = nodes;
    v.node_count = info.node_count;
    v.leaf_info = leaf_info;
    v.filled_leaves = info.filled_leaves;
    v.splats = splats;
    v.splat_count = static_cast<std::uint32_t>(info.splat_count);
    v.root_min = Vec3{info.root_min[0], info.root_min[1], info.root_min[2]};
    v.root_size = info.root_size;
    v.inv_root_size = 1.0f / info.root_size;
    v.flags = info.flags;
    return v;
}

/// Node word decoding (pool_layout.h encoding), callable from device code.
PRT_HD PRT_INLINE bool node_is_internal(std::uint32_t node) {
    return (node >> pool::k_node_address_bits) == static_cast<std::uint32_t>(pool::NodeType::internal);
}
PRT_HD PRT_INLINE bool node_is_filled(std::uint32_t node) {
    return (node >> pool::k_node_address_bits) == static_cast<std::uint32_t>(pool::NodeType::filled_leaf);
}
PRT_HD PRT_INLINE std::uint32_t node_addr(std::uint32_t node) {
    return node & pool::k_node_address_max;
}
inline constexpr std::uint32_t k_empty_leaf_node = static_cast<std::uint32_t>(pool::NodeType::empty_leaf)
                                                   << pool::k_node_address_bits;

/// Fixed-point coordinates of the walk's current point.
struct Fixed3 {
    std::uint32_t x, y, z;
};

PRT_HD PRT_INLINE std::uint32_t fixed_get(const Fixed3& p, int axis) {
    return axis == 0 ? p.x : (axis == 1 ? p.y : p.z);
}
PRT_HD PRT_INLINE void fixed_set(Fixed3& p, int axis, std::uint32_t v) {
    if (axis == 0)
        p.x = v;
    else if (axis == 1)
        p.y = v;
    else
        p.z = v;
}

/// Normalized coordinate q in [0,1] to fixed point, clamped to [0, k_fixed_max] (NaN gives 0).
PRT_HD PRT_INLINE std::uint32_t to_fixed(float q) {
    if (!(q > 0.0f)) return 0;
    if (q >= 1.0f) return k_fixed_max;
    const float s = q * static_cast<float>(k_fixed_one);  // exact scaling by a power of two
    const std::uint32_t v = static_cast<std::uint32_t>(s);
    return v > k_fixed_max ? k_fixed_max : v;
}

/// One leaf the ray crosses, with the ray parameter range inside the leaf's cell.
struct OctreeLeaf {
    std::uint32_t node;   ///< the node word (filled or empty leaf)
    std::uint32_t level;  ///< root = 0
    Fixed3 cell;          ///< the leaf's integer cell coordinates at its level
    float t0, t1;         ///< t0 <= t1
};

/// The state of one ray's walk through one octree.
struct OctreeWalk {
    Vec3 o;       ///< ray origin in normalized root coordinates
    Vec3 d;       ///< ray direction in normalized root coordinates (same t as the ray)
    Vec3 inv_d;   ///< 1 / d per axis (0 where d is 0), walk_step_out's plane crossings (PRT_WALK_RCP)
    Fixed3 p;     ///< current point (inside the next cell to visit)
    float t;      ///< ray parameter where the next cell is entered
    float t_end;  ///< min(t_max, the root's exit)
    float t_max;  ///< the ray's own bound: ray_misses_box tests the node boxes up to it
    std::uint32_t steps_left;
    std::uint32_t restart;                 ///< level of the deepest node shared with the next cell
    std::uint32_t path[k_fixed_bits + 1];  ///< node indices from the root to the current leaf
    bool active;
    bool truncated;  ///< the step bound ended the walk
};

/// Index of the lowest set bit (32 for 0), host and device.
PRT_HD PRT_INLINE std::uint32_t count_trailing_zeros(std::uint32_t v) {
#if PRT_DEVICE_CODE
    return v == 0 ? 32u : static_cast<std::uint32_t>(__ffs(static_cast<int>(v))) - 1u;
#else
    return v == 0 ? 32u : static_cast<std::uint32_t>(__builtin_ctz(v));
#endif
}

/// Index of the highest set bit's distance from bit 31 (32 for 0), host and device.
PRT_HD PRT_INLINE std::uint32_t count_leading_zeros(std::uint32_t v) {
#if PRT_DEVICE_CODE
    return static_cast<std::uint32_t>(__clz(static_cast<int>(v)));
#else
    return v == 0 ? 32u : static_cast<std::uint32_t>(__builtin_clz(v));
#endif
}

/// Starts a walk for the ray o + t d (model local frame), t in [t_min, t_max). Returns false when
/// the ray misses the root cube or is not finite.
PRT_HD inline bool walk_begin(const OctreeView& v, Vec3 o_local, Vec3 d_local, float t_min, float t_max,
                              std::uint32_t max_steps, OctreeWalk& w) {
    w.active = false;
    w.truncated = false;
    if (!is_finite(o_local) || !is_finite(d_local) || v.nodes == nullptr || v.node_count == 0) return false;
    w.o = (o_local - v.root_min) * v.inv_root_size;
    w.d = d_local * v.inv_root_size;
#if PRT_WALK_RCP
    w.inv_d = Vec3{0.0f, 0.0f, 0.0f};
#endif
    // Slab test against the unit cube [0,1]^3 (closed).
    float t_enter = t_min;
    float t_exit = t_max;
    int enter_axis = -1;
    PRT_UNROLL
    for (int a = 0; a < 3; ++a) {
        const float o = component(w.o, a);
        const float d = component(w.d, a);
        if (d == 0.0f) {
            if (!(o >= 0.0f && o <= 1.0f)) return false;
            continue;
        }
        const float inv = 1.0f / d;
#if PRT_WALK_RCP
        set_component(w.inv_d, a, inv);
#endif
        const float ta = (0.0f - o) * inv;
        const float tb = (1.0f - o) * inv;
        const float near = fminf(ta, tb);
        const float far = fmaxf(ta, tb);
        if (near > t_enter) {
            t_enter = near;
            enter_axis = a;
        }
        t_exit = fminf(t_exit, far);
    }
    if (!(t_enter <= t_exit)) return false;
    const Vec3 q = w.o + w.d * t_enter;
    w.p = Fixed3{to_fixed(q.x), to_fixed(q.y), to_fixed(q.z)};
    if (enter_axis >= 0) {
        // Entering through a root face: that coordinate is exactly on the face.
        fixed_set(w.p, enter_axis, component(w.d, enter_axis) > 0.0f ? 0u : k_fixed_max);
    }
    w.t = t_enter;
    w.t_end = t_exit;
    w.t_max = t_max;
    w.steps_left = max_steps;
    w.restart = 0;
    w.path[0] = 0;
    w.active = true;
    return true;
}

/// Reads a node word (through the read-only data cache on the GPU).
PRT_HD PRT_INLINE std::uint32_t load_node_word(const std::uint32_t* nodes, std::uint32_t index) {
#if PRT_DEVICE_CODE
    return __ldg(nodes + index);
#else
    return nodes[index];
#endif
}
PRT_HD PRT_INLINE std::uint32_t load_node(const OctreeView& v, std::uint32_t index) {
    return load_node_word(v.nodes, index);
}

/// Whether the walk's ray, t in [0, t_max], misses `box` widened by a margin of 1e-5 x (1 + the
/// largest |origin| coordinate) in normalized root coordinates: the walk's float ray differs from
/// the model-frame ray the splat tests use by rounding, about 1.2e-7 x (|origin| + t |d|) there.
/// All of [0, t_max] and not just the rest of the walk: a culled tree's leaf may hold the only copy
/// of a disk that the ray hits outside the leaf, even behind the walk (closest_hit_splats accepts
/// such hits from t = 0).
PRT_HD PRT_INLINE bool ray_misses_box(const OctreeWalk& w, const NodeBox* box) {
#if PRT_DEVICE_CODE
    const float2 b0 = __ldg(reinterpret_cast<const float2*>(box));
    const float2 b1 = __ldg(reinterpret_cast<const float2*>(box) + 1);
    const float2 b2 = __ldg(reinterpret_cast<const float2*>(box) + 2);
    const NodeBox b{{b0.x, b0.y, b1.x}, {b1.y, b2.x, b2.y}};
#else
    const NodeBox& b = *box;
#endif
    if (!(b.lo[0] <= b.hi[0])) return true;  // no hittable disk below the node
    const float m = 1e-5f * (1.0f + fmaxf(fmaxf(fabsf(w.o.x), fabsf(w.o.y)), fabsf(w.o.z)));
    float t0 = 0.0f, t1 = w.t_max;
    PRT_UNROLL
    for (int a = 0; a < 3; ++a) {
        const float d = component(w.d, a), o = component(w.o, a);
        const float lo = b.lo[a] - m, hi = b.hi[a] + m;
        if (d == 0.0f) {
            if (o < lo || o > hi) return true;
            continue;
        }
#if PRT_WALK_RCP
        const float inv = component(w.inv_d, a);
        const float ta = (lo - o) * inv, tb = (hi - o) * inv;
#else
        const float ta = (lo - o) / d, tb = (hi - o) / d;
#endif
        t0 = fmaxf(t0, fminf(ta, tb));
        t1 = fminf(t1, fmaxf(ta, tb));
    }
    return t0 > t1;
}

/// thesis 2.2.2: descends top-down to the leaf holding fixed-point point `p`, starting at the
/// node path[level] (path[0] = 0 is the root) and recording the nodes passed in `path`. Returns
/// the leaf's node word and sets `level` to its level. Corrupt addresses and trees deeper than
/// k_fixed_bits end in an empty leaf instead of reading out of bounds (the pool reader validates
/// addresses already). `Boxed`: with the view's node boxes and the walk `w` (descend_boxed).
template <bool Boxed>
PRT_HD PRT_INLINE std::uint32_t descend_path(const OctreeView& v, const Fixed3& p, const OctreeWalk* w,
                                             std::uint32_t* path, std::uint32_t& level) {
    std::uint32_t l = level;
    std::uint32_t node = load_node(v, path[l]);
    while (node_is_internal(node)) {  // bounded: l < k_fixed_bits
        const std::uint32_t addr = node_addr(node);
        if (l >= k_fixed_bits || addr >= v.node_count || v.node_count - addr < 8u) {
            node = k_empty_leaf_node;
            break;
        }
        const std::uint32_t shift = k_fixed_bits - 1u - l;
        const std::uint32_t c =
            ((p.x >> shift) & 1u) | (((p.y >> shift) & 1u) << 1) | (((p.z >> shift) & 1u) << 2);
        path[++l] = addr + c;
        if constexpr (Boxed) {
            // The mask is read beside the child's word (both addresses are known here); only a
            // child whose box is worth it costs the dependent read of its box.
#if PRT_DEVICE_CODE
            const std::uint32_t mask = __ldg(v.node_box_mask + ((addr - 1u) >> 3));
#else
            const std::uint32_t mask = v.node_box_mask[(addr - 1u) >> 3];
#endif
            node = load_node(v, addr + c);
            if (((mask >> c) & 1u) != 0u && node_is_internal(node) &&
                ray_misses_box(*w, v.node_boxes + ((node_addr(node) - 1u) >> 3))) {
                node = k_empty_leaf_node;
                break;
            }
        } else {
            node = load_node(v, addr + c);
        }
    }
    level = l;
    return node;
}

PRT_HD PRT_INLINE std::uint32_t descend(const OctreeView& v, const Fixed3& p, std::uint32_t* path,
                                        std::uint32_t& level) {
    return descend_path<false>(v, p, nullptr, path, level);
}

/// descend() with node boxes: an internal node whose disks the ray misses altogether (its
/// NodeBox) is taken as an empty leaf, so the walk steps over its cell at once instead of visiting
/// the leaves below it. Exact: a leaf under such a node holds no disk the ray can hit. Only the
/// children the mask marks are tested: testing every internal child, the H200's splat kernel took
/// the culled 1M room's primary rays from 19.9 to 15.3 leaves and 1.49 to 1.66 Grays/s (full4 0.94
/// -> 1.18) but the culled 10M sphere's from 1.23 to 1.12, whose boxes most rays meet (a dependent
/// read per level for little); with the mask 1.59-1.60 (full4 1.15) and 1.20-1.21
/// (preprocess/bench/results/h200-2026-12-03-issue19-io-boxes).
PRT_HD PRT_INLINE std::uint32_t descend_boxed(const OctreeView& v, const OctreeWalk& w, std::uint32_t* path,
                                              std::uint32_t& level) {
    return descend_path<true>(v, w.p, &w, path, level);
}

/// thesis 2.2.2: the leaf holding fixed-point point `p`, descending from the root.
PRT_HD PRT_INLINE std::uint32_t find_leaf(const OctreeView& v, const Fixed3& p, std::uint32_t& level) {
    std::uint32_t path[k_fixed_bits + 1];
    path[0] = 0;
    level = 0;
    return descend(v, p, path, level);
}

/// thesis 2.2.1: the walk's step out of the leaf `node` found at `level` (the descent of walk_next):
/// the leaf's cell and t range into `leaf`, then the point moved into the neighbour across the exit
/// face. Returns true (the leaf is valid); the walk is left inactive when the ray leaves the root or
/// passes t_end. Shared by walk_next and the bricked walk (bricks.h), which descend differently.
/// With a macro-region `r` (an empty leaf's, MacroRegion), the walk leaves through the region's exit
/// face instead of the cell's (the leaf's own cell, level and t0 are reported as before; its t1 is
/// the region's exit). The builder keeps the region inside the root; the clamps here keep a region
/// that is not from leaving it all the same.
PRT_HD PRT_INLINE bool walk_step_out(OctreeWalk& w, std::uint32_t node, std::uint32_t level, OctreeLeaf& leaf,
                                     MacroRegion r = MacroRegion{}) {
    const std::uint32_t shift = k_fixed_bits - level;
    const Fixed3 cell{w.p.x >> shift, w.p.y >> shift, w.p.z >> shift};
    const float size = exp2_neg(level);
    // The cells at this level the step leaves: [first, last] per axis (the leaf's cell, or its
    // macro-region).
    const std::uint32_t cells = 1u << level;
    Fixed3 first = cell, last = cell;
    PRT_UNROLL
    for (int a = 0; a < 3; ++a) {
        const std::uint32_t c = fixed_get(cell, a);
        fixed_set(first, a, c - (r.below[a] < c ? r.below[a] : c));
        const std::uint32_t room = cells - 1u - c;
        fixed_set(last, a, c + (r.above[a] < room ? r.above[a] : room));
    }
    // Where the ray leaves the cells: the nearest of the three axis-plane crossings.
    float t1 = k_inf;
    int axis = 0;
    PRT_UNROLL
    for (int a = 0; a < 3; ++a) {
        const float d = component(w.d, a);
        if (d == 0.0f) continue;
        const float plane = (d > 0.0f ? static_cast<float>(fixed_get(last, a)) + 1.0f
                                      : static_cast<float>(fixed_get(first, a))) *
                            size;
#if !PRT_WALK_RCP
        const float ta = (plane - component(w.o, a)) / d;
#else
        // Multiplies by the walk's 1 / d (the host; device code only with PRT_DEVICE_WALK_RCP):
        // three divisions a step were the largest cost of the CPU walk's step (perf on
        // prt-bench-embree's room). t orders hits and bounds a leaf's
        // range only; which cell comes next is integer arithmetic, so the walk is as robust.
        const float ta = (plane - component(w.o, a)) * component(w.inv_d, a);
#endif
        if (ta < t1) {
            t1 = ta;
            axis = a;
        }
    }
    const float t0 = w.t;
    if (!(t1 >= t0)) t1 = t0;  // rounding in tiny cells: keep t monotone
    leaf.node = node;
    leaf.level = level;
    leaf.cell = cell;
    leaf.t0 = t0;
    leaf.t1 = fminf(t1, w.t_end);
    if (t1 >= w.t_end) {
        w.active = false;
        return true;
    }
    // Step into the neighbour across the exit face by integer arithmetic.
    const Fixed3 old = w.p;
    if (component(w.d, axis) > 0.0f) {
        const std::uint32_t next = (fixed_get(last, axis) + 1u) << shift;  // level 0: 1 << 30 = outside
        if (level == 0 || next > k_fixed_max) {
            w.active = false;
            return true;
        }
        fixed_set(w.p, axis, next);
    } else {
        const std::uint32_t ca = fixed_get(first, axis);
        if (ca == 0u) {
            w.active = false;
            return true;
        }
        fixed_set(w.p, axis, (ca << shift) - 1u);
    }
    PRT_UNROLL
    for (int b = 0; b < 3; ++b) {
        if (b == axis) continue;
        const float d = component(w.d, b);
        if (d == 0.0f) continue;  // axis-parallel: the coordinate never changes
        std::uint32_t f = to_fixed(component(w.o, b) + d * t1);
        const std::uint32_t old = fixed_get(w.p, b);
        const std::uint32_t lo = fixed_get(first, b) << shift;
        const std::uint32_t hi = ((fixed_get(last, b) + 1u) << shift) - 1u;  // level 0: 2^30 - 1
        if (d > 0.0f) {
            f = f < old ? old : f;  // never backwards along the ray
            f = f > hi ? hi : f;    // stay within the current cell's extent
        } else {
            f = f > old ? old : f;
            f = f < lo ? lo : f;
        }
        fixed_set(w.p, b, f);
    }
    // The child choices at levels above the highest changed bit are the same as before: the next
    // descent may start at that ancestor (bit k_fixed_bits-1-l picks the child at level l).
    const std::uint32_t changed = (old.x ^ w.p.x) | (old.y ^ w.p.y) | (old.z ^ w.p.z);
    const std::uint32_t shared = count_leading_zeros(changed) - (32u - k_fixed_bits);
    w.restart = shared < level ? shared : level;
    w.t = t1;
    return true;
}

/// Reads a macro-region (one 8-byte read-only load on the GPU).
PRT_HD PRT_INLINE MacroRegion load_macro_region(const MacroRegion* p) {
#if PRT_DEVICE_CODE
    const uint2 a = __ldg(reinterpret_cast<const uint2*>(p));
    MacroRegion r;
    memcpy(&r, &a, sizeof(a));
    return r;
#else
    return *p;
#endif
}

/// thesis 2.2.1: one step of a walk: the bound on steps, then `descend(level)` (from level =
/// w.restart, returning the leaf's node word and setting its level), then walk_step_out. Shared by
/// walk_next and the bricked walk (bricks.h), which descend differently. `regions`
/// (OctreeView::macro_regions, or null): an empty leaf whose word carries an address a > 0 is left
/// through regions[k_region_axes a + region_axis(w.d)].
template <class Descend>
PRT_HD PRT_INLINE bool walk_step(OctreeWalk& w, OctreeLeaf& leaf, Descend&& descend,
                                 const MacroRegion* regions = nullptr) {
    if (!w.active) return false;
    if (w.steps_left == 0) {
        w.active = false;
        w.truncated = true;
        return false;
    }
    --w.steps_left;
    std::uint32_t level = w.restart;
    const std::uint32_t node = descend(level);
    MacroRegion r{};
    if (regions != nullptr && node_addr(node) != 0u && !node_is_filled(node))
        r = load_macro_region(regions + k_region_axes * node_addr(node) + region_axis(w.d));
    return walk_step_out(w, node, level, leaf, r);
}

/// thesis 2.2.1: the next leaf along the walk (front to back), or false when the ray has left the
/// root, passed t_max or used up its steps. Top-down descent (thesis 2.2.2), from the deepest node
/// the previous leaf's path shares with this cell rather than from the root: the same leaf, found
/// with fewer dependent reads. Always inlined: g++ once left it a call per step in the host's splat
/// walks (63 % of a CPU frame's samples). With the view's node boxes, descend_boxed; with its
/// macro-regions, an empty leaf that has one is left through it. `k_regions` false: the walk
/// compiled without the macro-region code (leaf by leaf, the view's regions unread), for kernels
/// that trace scenes where regions do not pay (core::k_mask_plain_walk).
template <bool k_regions = true>
PRT_HD PRT_INLINE bool walk_next(const OctreeView& v, OctreeWalk& w, OctreeLeaf& leaf) {
    const MacroRegion* regions = k_regions ? v.macro_regions : nullptr;
    if (v.node_boxes != nullptr)
        return walk_step(
            w, leaf, [&](std::uint32_t& level) { return descend_boxed(v, w, w.path, level); }, regions);
    return walk_step(
        w, leaf, [&](std::uint32_t& level) { return descend(v, w.p, w.path, level); }, regions);
}

/// The splat index range [begin, end) of a filled leaf, clamped to the arrays (empty if invalid).
PRT_HD PRT_INLINE void leaf_splats(const OctreeView& v, std::uint32_t node, std::uint32_t& begin,
                                   std::uint32_t& end) {
    begin = end = 0;
    if (!node_is_filled(node)) return;
    const std::uint32_t a = node_addr(node);
    if (a >= v.filled_leaves) return;
    begin = v.leaf_info[a];
    end = v.leaf_info[a + 1];
    if (end > v.splat_count) end = v.splat_count;
    if (begin > end) begin = end;
}

}  // namespace prt::core
