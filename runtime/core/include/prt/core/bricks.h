// PointRT core: tracing a bricked splat pool (issue 17; formats/POOL.md "Bricks and level of
// detail"). Two levels of the same octree walk (octree.h, thesis 2.2):
//
//   outer: the resident top tree (brick_top_nodes, root cube of brick_info), where a brick node
//          (NodeType::brick) is a leaf;
//   inner: at a brick leaf, the brick's own subtree (node addresses relative to the brick, root
//          cube = the BrickEntry cube), walked over the outer leaf's t range [t0, t1]; its filled
//          leaves' compressed splats are decoded on the fly (brick_layout.h) and go through the
//          float path's leaf code (splat.h: intersect_splat, thesis 3.3 blending, thesis 3.5 deep
//          blending across leaves and bricks alike).
//
// Which bricks are resident is the view's `resident` table (null: every brick, at data + offset),
// so streaming changes only that table. A ray reaching a brick that is not resident intersects the
// brick's level-of-detail disc (lod_splats[top node]) as one splat, hits accepted from t = 0 to the
// end of the brick's cell, counts a fallback and, when the view has a request array, flags the
// brick. Colours come from the splats (RGB565; white in a pool without colors); bricks carry no
// source point, so hits shade with the model's material.
#pragma once

#include <cstdint>

#include "prt/core/math.h"
#include "prt/core/octree.h"
#include "prt/core/splat.h"
#include "prt/formats/brick_layout.h"

namespace prt::core {

/// A non-owning view of a model's brick sections (pool section types 128-132) and of which bricks
/// are resident. Host pointers on the CPU, device pointers in a kernel.
struct BrickView {
    const std::uint32_t* top_nodes = nullptr;  ///< brick_top_nodes, top_node_count words; null: no bricks
    std::uint32_t top_node_count = 0;
    const pool::BrickEntry* table = nullptr;  ///< brick_table, brick_count entries
    std::uint32_t brick_count = 0;
    const unsigned char* data = nullptr;  ///< brick_data: brick b at data + table[b].offset
    std::uint64_t data_bytes = 0;
    const pool::LodSplat* lod = nullptr;  ///< lod_splats, parallel to top_nodes
    /// Per brick: its payload's address, or null when it is not resident. A null table: every
    /// brick is resident at data + table[b].offset.
    const unsigned char* const* resident = nullptr;
    /// Per brick, or null: set to 1 when a ray fell back to the brick's LOD disc (streaming requests).
    std::uint32_t* requests = nullptr;
    /// Per brick, or null: set to 1 when a ray opened the resident brick (streaming: the bricks a
    /// frame used are not evicted, the others leave least recently used first; rt::BrickStream).
    std::uint32_t* used = nullptr;
    /// Per filled leaf of every brick, or null: LeafBounds (octree.h) over the decoded splats, so
    /// rays pass leaves unread as on the float path; brick b's at leaf_bounds + leaf_bounds_first[b].
    /// Derived on the host at load (rt::build_brick_leaf_bounds), not in the pool.
    const LeafBounds* leaf_bounds = nullptr;
    const std::uint32_t* leaf_bounds_first = nullptr;
    Vec3 root_min{0, 0, 0};  ///< root cube of the whole tree, model local frame
    float root_size = 1.0f;
    float inv_root_size = 1.0f;
    std::uint32_t flags = 0;  ///< pool::BrickFlags
};

/// The brick view over a pool's validated brick sections, every brick resident. Host only.
inline BrickView make_brick_view(const pool::BrickInfo& info, const std::uint32_t* top_nodes,
                                 const pool::BrickEntry* table, const unsigned char* data,
                                 std::uint64_t data_bytes, const pool::LodSplat* lod) {
    return BrickView{.top_nodes = top_nodes,
                     .top_node_count = info.top_node_count,
                     .table = table,
                     .brick_count = info.brick_count,
                     .data = data,
                     .data_bytes = data_bytes,
                     .lod = lod,
                     .root_min = Vec3{info.root_min[0], info.root_min[1], info.root_min[2]},
                     .root_size = info.root_size,
                     .inv_root_size = 1.0f / info.root_size,
                     .flags = info.flags};
}

/// A brick node of the top tree: node type 3, address = brick index.
PRT_HD PRT_INLINE bool node_is_brick(std::uint32_t node) {
    return (node >> pool::k_node_address_bits) == static_cast<std::uint32_t>(pool::NodeType::brick);
}

/// Splats decoded from a brick (bricks.h): `point` holds the splat's RGB565 colour, so color()
/// decodes it; bricks carry no source point (point_id: none).
struct Rgb565Splats {
    PRT_HD PRT_INLINE Vec3 color(std::uint32_t point) const {
        const pool::Rgba8 c = pool::decode_rgb565(static_cast<std::uint16_t>(point));
        constexpr float k = 1.0f / 255.0f;
        return Vec3{c.r * k, c.g * k, c.b * k};
    }
    PRT_HD PRT_INLINE std::uint32_t point_id(std::uint32_t) const { return 0xffffffffu; }
};

/// A resident brick's compressed splats, decoded on load (brick_layout.h: decode_splat).
struct BrickSplats : Rgb565Splats {
    const pool::CompressedSplat* splats;
    pool::BrickHeader header;
    PRT_HD PRT_INLINE pool::Splat load(std::uint32_t i) const {
        const pool::DecodedSplat d = pool::decode_splat(splats[i], header);
        return pool::Splat{d.position, d.radius, d.normal, splats[i].color};
    }
};

/// One level-of-detail disc as a one-splat leaf (its colour rounded to RGB565, as a brick's).
struct LodSplats : Rgb565Splats {
    pool::Splat disc;
    PRT_HD PRT_INLINE pool::Splat load(std::uint32_t) const { return disc; }
};

/// Brick b's resident payload, or null.
PRT_HD PRT_INLINE const unsigned char* brick_payload(const BrickView& v, std::uint32_t b) {
    if (v.resident != nullptr) return v.resident[b];
    return v.data + v.table[b].offset;
}

/// The octree view of a resident brick (node 0 its root, the entry's cube), for the walk of
/// octree.h; its splats are read through BrickSplats, not the view.
PRT_HD PRT_INLINE OctreeView brick_octree(const pool::BrickEntry& e, const pool::BrickHeader& h,
                                          const unsigned char* payload) {
    OctreeView v;
    v.nodes = reinterpret_cast<const std::uint32_t*>(payload + pool::brick_nodes_offset());
    v.node_count = h.node_count;
    v.leaf_info =
        reinterpret_cast<const std::uint32_t*>(payload + pool::brick_leaf_info_offset(h.node_count));
    v.filled_leaves = h.leaf_count;
    v.splats = nullptr;
    v.splat_count = h.splat_count;
    v.root_min = Vec3{e.cube_min[0], e.cube_min[1], e.cube_min[2]};
    v.root_size = e.cube_size;
    v.inv_root_size = 1.0f / e.cube_size;
    return v;
}

/// The top tree as an octree view (brick nodes are leaves of it).
PRT_HD PRT_INLINE OctreeView brick_top_octree(const BrickView& v) {
    OctreeView t;
    t.nodes = v.top_nodes;
    t.node_count = v.top_node_count;
    t.root_min = v.root_min;
    t.root_size = v.root_size;
    t.inv_root_size = v.inv_root_size;
    return t;
}

/// The LOD disc of top node `node` as a one-splat source; false for an empty disc.
PRT_HD PRT_INLINE bool lod_disc(const BrickView& v, std::uint32_t node, LodSplats& out) {
    if (v.lod == nullptr || node >= v.top_node_count) return false;
    const pool::LodSplat l = v.lod[node];
    if (!(l.radius > 0.0f)) return false;
    out.disc = pool::Splat{l.position, l.radius, l.normal, pool::encode_rgb565(l.color)};
    return true;
}

/// Sets flags[b] to 1 (streaming's request and use flags; many rays set the same flag: it is read
/// first, so a flag already set costs no write).
PRT_HD PRT_INLINE void flag_brick(std::uint32_t* flags, std::uint32_t b) {
#if PRT_DEVICE_CODE
    if (flags[b] == 0u) flags[b] = 1u;
#else
    if (__atomic_load_n(flags + b, __ATOMIC_RELAXED) == 0u) __atomic_store_n(flags + b, 1u, __ATOMIC_RELAXED);
#endif
}

/// Counts a fallback to brick b's LOD disc and flags its request (streaming).
PRT_HD PRT_INLINE void note_fallback(const BrickView& v, std::uint32_t b, WalkStats& stats) {
    ++stats.fallbacks;
    if (v.requests != nullptr) flag_brick(v.requests, b);
}

/// Opens resident brick b: its splat source and octree view (with its leaf bounds when the view
/// has them), flagging it used when the view has use flags. False when b is out of range or not
/// resident.
PRT_HD PRT_INLINE bool open_brick(const BrickView& v, std::uint32_t b, BrickSplats& src, OctreeView& brick) {
    if (b >= v.brick_count) return false;
    const unsigned char* payload = brick_payload(v, b);
    if (payload == nullptr) return false;
    if (v.used != nullptr) flag_brick(v.used, b);
    src.header = *reinterpret_cast<const pool::BrickHeader*>(payload);
    src.splats = reinterpret_cast<const pool::CompressedSplat*>(
        payload + pool::brick_splats_offset(src.header.node_count, src.header.leaf_count));
    brick = brick_octree(v.table[b], src.header, payload);
    if (v.leaf_bounds != nullptr) brick.leaf_bounds = v.leaf_bounds + v.leaf_bounds_first[b];
    return true;
}

/// One brick leaf of the top tree, the way both searches meet it: calls `resident(src, inner_view)`
/// for a resident brick, or `fallback(lod)` for a brick that is not (after noting the fallback; a
/// brick whose disc is empty is passed). Returns what the call returned (true: stop).
template <class Resident, class Fallback>
PRT_HD PRT_INLINE bool visit_brick(const BrickView& v, std::uint32_t b, std::uint32_t top_node,
                                   WalkStats& stats, Resident&& resident, Fallback&& fallback) {
    if (b >= v.brick_count) return false;
    BrickSplats src;
    OctreeView brick;
    if (open_brick(v, b, src, brick)) return resident(src, brick);
    note_fallback(v, b, stats);
    LodSplats lod;
    return lod_disc(v, top_node, lod) && fallback(lod);
}

/// The inner walk of a resident brick over the outer leaf's t range [t0, t1], with the steps the
/// outer walk has left: search(inner walk, leaf bounds or null) does the leaf work and says whether
/// the search is over. A truncated inner walk ends the outer one.
template <class Search>
PRT_HD PRT_INLINE bool walk_brick(const OctreeView& brick, const OctreeLeaf& leaf, Vec3 o, Vec3 d,
                                  OctreeWalk& walk, std::uint32_t culling, Search&& search) {
    OctreeWalk inner;
    if (!walk_begin(brick, o, d, leaf.t0, leaf.t1, walk.steps_left, inner)) return false;
    const bool over = search(inner, culling != k_cull_none ? brick.leaf_bounds : nullptr);
    walk.steps_left = inner.steps_left;
    if (inner.truncated) walk.truncated = true, walk.active = false;
    return over;
}

/// Closest hit of a ray with a bricked model's splats (model local frame; d need not be unit), as
/// closest_hit_splats does it over the float octree: t in [0, t_max), the same blending. Returns
/// false on a miss. `max_steps` bounds the leaves of both levels together.
PRT_HD inline bool closest_hit_bricks(const BrickView& v, Vec3 o, Vec3 d, bool inside, float t_max,
                                      const BlendOptions& blend, std::uint32_t max_steps, SplatSample& out,
                                      WalkStats& stats, std::uint32_t culling = k_cull_slabs) {
    const OctreeView top = brick_top_octree(v);
    OctreeWalk walk;
    if (!walk_begin(top, o, d, 0.0f, t_max, max_steps, walk)) return false;
    // Without the flag (prt-octree --no-replicate) each disk is in one leaf only: hits from t = 0.
    const bool replicated = (v.flags & pool::k_bricks_replicated) != 0;
    const float inv_dlen = 1.0f / length(d);
    detail::NearestHit h;
    OctreeLeaf leaf;
    while (walk_next(top, walk, leaf)) {  // bounded by max_steps
        PRT_COUNT(stats.leaves);
        if (h.found && leaf.t0 > h.window_end) break;
        if (!node_is_brick(leaf.node)) continue;  // empty leaf
        const bool stop = visit_brick(
            v, node_addr(leaf.node), walk.path[leaf.level], stats,
            [&](const BrickSplats& src, const OctreeView& brick) {
                return walk_brick(
                    brick, leaf, o, d, walk, culling, [&](OctreeWalk& inner, const LeafBounds* bounds) {
                        return closest_in_walk(brick, inner, src, bounds, culling, o, d, inv_dlen, inside,
                                               replicated, t_max, blend, h, stats);
                    });
            },
            [&](const LodSplats& lod) {
                return detail::closest_in_leaf(lod, 0, 1, o, d, inside, inv_dlen, h.found ? h.t_near : 0.0f,
                                               fminf(leaf.t1, t_max), blend, h, stats);
            });
        if (stop) break;
    }
    if (walk.truncated) ++stats.truncated;
    return detail::finish_nearest(Rgb565Splats{}, h, out);
}

/// Any hit of a ray with a bricked model's splats in t in [0, t_max) (shadow rays, thesis 5.2), as
/// any_hit_splats does it over the float octree.
PRT_HD inline bool any_hit_bricks(const BrickView& v, Vec3 o, Vec3 d, bool inside, float t_max,
                                  std::uint32_t max_steps, WalkStats& stats,
                                  std::uint32_t culling = k_cull_slabs) {
    const OctreeView top = brick_top_octree(v);
    OctreeWalk walk;
    if (!walk_begin(top, o, d, 0.0f, t_max, max_steps, walk)) return false;
    const float hi = nextafterf(t_max, 0.0f);
    const float inv_dlen = 1.0f / length(d);
    const bool own_range =
        (v.flags & pool::k_bricks_replicated) != 0 && (v.flags & pool::k_bricks_culled) == 0;
    OctreeLeaf leaf;
    bool hit = false;
    while (!hit && walk_next(top, walk, leaf)) {  // bounded by max_steps
        PRT_COUNT(stats.leaves);
        if (!node_is_brick(leaf.node)) continue;
        hit = visit_brick(
            v, node_addr(leaf.node), walk.path[leaf.level], stats,
            [&](const BrickSplats& src, const OctreeView& brick) {
                return walk_brick(brick, leaf, o, d, walk, culling,
                                  [&](OctreeWalk& inner, const LeafBounds* bounds) {
                                      return any_in_walk(brick, inner, src, bounds, culling, o, d, inv_dlen,
                                                         inside, own_range, hi, stats);
                                  });
            },
            [&](const LodSplats& lod) {
                return detail::any_in_leaf(lod, 0, 1, o, d, inside, 0.0f, fminf(leaf.t1, hi), stats);
            });
    }
    if (walk.truncated) ++stats.truncated;
    return hit;
}

}  // namespace prt::core
