// PointRT core: tracing a bricked splat pool (issue 17; formats/POOL.md "Bricks and level of
// detail"). One octree walk (octree.h, thesis 2.2) over the whole tree, whose nodes live in two
// places: the resident top tree (brick_top_nodes, root cube of brick_info), where a brick node
// (NodeType::brick) addresses a brick, and each brick's own subtree (node addresses relative to the
// brick, its root at the brick node's level and cube). The descent (descend_bricked) continues from
// a brick node into the brick's node 0 and remembers the brick (BrickCursor); the walk's path above
// the brick's level indexes the brick's nodes, so the walk steps from leaf to leaf across bricks as
// across the float octree, with one walk state. Filled leaves' compressed splats are decoded on the
// fly (brick_layout.h) and go through the float path's leaf code (splat.h: intersect_splat, thesis
// 3.3 blending, thesis 3.5 deep blending across leaves and bricks alike).
//
// Level of detail: a ray has a footprint (LodCone: width + spread * t; the renderer's rays a pixel's
// angle times the distance from their origin, RenderParams::lod_spread). The descent stops at the first node
// whose cell is no wider than the footprint where the walk enters it, if the node has a disc: a top node
// (lod_splats) or a node of a brick's LOD prefix (brick_lod, lod_nodes, lod_discs: the brick's top levels,
// resident with the top tree). The node's disc is then met as one splat inside the node's cell. Which node a
// ray stops at depends only on the ray and the resident index, never on which bricks are resident, so a
// streamed view converges to the in-core image.
//
// Which bricks are resident is the view's `resident` table (null: every brick, at data + offset),
// so streaming changes only that table. A resident brick's first nodes are its prefix (the stops
// there read the prefix's discs); the descent walks a missing brick's prefix from its resident
// copy, and a ray that needs a brick that is not resident meets
// the deepest disc it reached (the prefix node, else the brick's top-node disc) inside that node's
// cell, counts a fallback and, when the view has a request array and it is the first missing brick
// on the ray's way, flags the brick (a resident brick is flagged used where the walk needs its
// payload, up to that first missing brick: stopped_at_disc says why). Colours come from
// the splats (RGB565; white in a pool without colors); bricks carry no source point, so hits shade
// with the model's material.
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
    /// Brick LOD prefixes (brick_lod per brick, lod_nodes and lod_discs), or null: resident with the
    /// top tree (streaming never evicts them).
    const pool::BrickLod* lod_table = nullptr;
    const std::uint32_t* lod_nodes = nullptr;
    const pool::CompressedSplat* lod_discs = nullptr;
    std::uint32_t lod_node_count = 0;
    /// Streamed prefixes (rt::BrickStream, when the prefixes do not all fit the budget), or null:
    /// per brick, where its resident prefix's node words start in lod_nodes (then the storage's
    /// arena, as words): the word before holds how many (K: the whole prefix, lod_table[b].node_count,
    /// or its coarse part, the breadth-first levels above its deepest), then K node words, then K
    /// discs; k_prefix_missing when it is not resident (lod_discs unused). Null: every prefix
    /// resident at lod_table[b].first of lod_nodes and lod_discs. A brick whose payload is resident
    /// has its whole prefix resident too (so where a ray stops never depends on residency).
    const std::uint32_t* prefix_first = nullptr;
    /// Per brick, or null (with prefix_first): set to 1 when a ray's walk entered the brick's
    /// resident prefix (up to the first missing brick on its way), so it is not evicted.
    std::uint32_t* prefix_used = nullptr;
    /// Per brick: its payload's address, or null when it is not resident. A null table: every
    /// brick is resident at data + table[b].offset.
    const unsigned char* const* resident = nullptr;
    /// Per brick, or null: set to 1 when a ray fell back to the brick's LOD disc (streaming requests).
    std::uint32_t* requests = nullptr;
    /// Per brick, or null: set to 1 when a ray needed the resident brick's payload (a filled leaf or
    /// a node below its LOD prefix: where it would have requested the brick were it missing), so
    /// the bricks a frame used are not evicted, the others leave least recently used first
    /// (rt::BrickStream). A walk that stays in the prefix does not keep the brick.
    std::uint32_t* used = nullptr;
    /// Per filled leaf of every brick, or null: BrickLeafBounds (octree.h, 16 bytes) over the decoded
    /// splats, so rays pass leaves unread as on the float path; brick b's at leaf_bounds +
    /// leaf_bounds_first[b]. Derived at load or upload (rt::build_brick_leaf_bounds, the CUDA
    /// storage's derive_brick_leaf_bounds), not in the pool.
    const BrickLeafBounds* leaf_bounds = nullptr;
    const std::uint32_t* leaf_bounds_first = nullptr;
    Vec3 root_min{0, 0, 0};  ///< root cube of the whole tree, model local frame
    float root_size = 1.0f;
    float inv_root_size = 1.0f;
    std::uint32_t flags = 0;  ///< pool::BrickFlags
};

/// The brick view over a pool's validated brick sections, every brick resident (LOD prefixes: null
/// when the pool has none). Host only.
inline BrickView make_brick_view(const pool::BrickInfo& info, const std::uint32_t* top_nodes,
                                 const pool::BrickEntry* table, const unsigned char* data,
                                 std::uint64_t data_bytes, const pool::LodSplat* lod,
                                 const pool::BrickLod* lod_table = nullptr,
                                 const std::uint32_t* lod_nodes = nullptr,
                                 const pool::CompressedSplat* lod_discs = nullptr,
                                 std::uint32_t lod_node_count = 0) {
    return BrickView{.top_nodes = top_nodes,
                     .top_node_count = info.top_node_count,
                     .table = table,
                     .brick_count = info.brick_count,
                     .data = data,
                     .data_bytes = data_bytes,
                     .lod = lod,
                     .lod_table = lod_table,
                     .lod_nodes = lod_nodes,
                     .lod_discs = lod_discs,
                     .lod_node_count = lod_node_count,
                     .root_min = Vec3{info.root_min[0], info.root_min[1], info.root_min[2]},
                     .root_size = info.root_size,
                     .inv_root_size = 1.0f / info.root_size,
                     .flags = info.flags};
}

/// BrickView::prefix_first of a brick whose prefix is not resident.
inline constexpr std::uint32_t k_prefix_missing = 0xffffffffu;

/// A brick node of the top tree: node type 3, address = brick index.
PRT_HD PRT_INLINE bool node_is_brick(std::uint32_t node) {
    return (node >> pool::k_node_address_bits) == static_cast<std::uint32_t>(pool::NodeType::brick);
}

/// Splats decoded from a brick (bricks.h): `point` holds the splat's RGB565 colour, so color()
/// decodes it; bricks carry no source point (point_id: none).
struct Rgb565Splats {
    /// The RGB565 colour as it is stored, each channel its code over the code range (r / 31, g / 63,
    /// b / 31), rather than through decode_rgb565's 8-bit rounding (within 0.5 / 255 of it): the
    /// blend decodes one colour per blended splat, and the integer divisions of the 8-bit path made
    /// the colour decode 5 % of the bricked kernel's instructions (ncu, room primary, H200).
    PRT_HD PRT_INLINE Vec3 color(std::uint32_t point) const {
        return Vec3{float((point >> 11) & 31u) * (1.0f / 31.0f), float((point >> 5) & 63u) * (1.0f / 63.0f),
                    float(point & 31u) * (1.0f / 31.0f)};
    }
    PRT_HD PRT_INLINE std::uint32_t point_id(std::uint32_t) const { return 0xffffffffu; }
    /// A loaded normal as a unit vector (splat.h blends unit normals): LOD discs' are unit already.
    PRT_HD PRT_INLINE Vec3 unit(Vec3 n) const { return n; }
};

/// A resident brick's compressed splats, decoded on load (brick_layout.h: decode_splat). Leaves
/// index references (splat i of the leaves is encoded splat refs[i]: 16-bit, or 32-bit in a brick
/// of more than 65536 encoded splats), so a splat held by several leaves is stored once; a direct
/// brick (ref_bytes 0) stores its leaves' splats in leaf order, so splat i is read with no reference.
struct BrickSplats : Rgb565Splats {
    const pool::CompressedSplat* splats;
    const void* refs;
    std::uint32_t ref_bytes;  ///< 2, 4, or 0: direct
    pool::BrickHeader header;
    float step;  ///< header.quant_size / 65535: decode_coordinate's step, divided once per brick
    PRT_HD PRT_INLINE std::uint32_t ref(std::uint32_t i) const {
        if (ref_bytes == 0u) return i;
        if (ref_bytes == 2u) return static_cast<const std::uint16_t*>(refs)[i];
        return static_cast<const std::uint32_t*>(refs)[i];
    }
    /// Splat i as decode_splat gives it, but its normal the octahedral point (not unit: the
    /// ray-plane test of intersect_splat and the leaf bounds do not need it unit; unit() below
    /// normalizes the normals splat.h blends, as decode_octahedral would).
    PRT_HD PRT_INLINE pool::Splat load(std::uint32_t i) const {
        const pool::CompressedSplat c = splats[ref(i)];
        const float* lo = header.quant_min;
        const pool::Float3 p{lo[0] + float(c.q[0]) * step, lo[1] + float(c.q[1]) * step,
                             lo[2] + float(c.q[2]) * step};
        return pool::Splat{p, pool::decode_radius(c.nr >> 20, header.quant_size, header.radius_log2_min),
                           pool::decode_octahedral_point(c.nr & 0xFFFFFu), c.color};
    }
    PRT_HD PRT_INLINE Vec3 unit(Vec3 n) const {
        const pool::Float3 u = pool::normalize_octahedral(pool::Float3{n.x, n.y, n.z});
        return Vec3{u.x, u.y, u.z};
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

/// Sets flags[b] to 1 (streaming's request and use flags; many rays set the same flag: it is read
/// first, so a flag already set costs no write).
PRT_HD PRT_INLINE void flag_brick(std::uint32_t* flags, std::uint32_t b) {
#if PRT_DEVICE_CODE
    if (flags[b] == 0u) flags[b] = 1u;
#else
    if (__atomic_load_n(flags + b, __ATOMIC_RELAXED) == 0u) __atomic_store_n(flags + b, 1u, __ATOMIC_RELAXED);
#endif
}

/// The splat source of a resident brick's payload.
PRT_HD PRT_INLINE BrickSplats brick_splats(const unsigned char* payload) {
    BrickSplats src;
    src.header = *reinterpret_cast<const pool::BrickHeader*>(payload);
    const pool::BrickHeader& h = src.header;
    const bool direct = pool::brick_is_direct(h);
    src.refs = payload + pool::brick_refs_offset(h.node_count, h.leaf_count);
    src.ref_bytes = direct ? 0u : pool::brick_ref_bytes(h.encoded_count);
    src.step = h.quant_size / pool::k_position_max_code;
    src.splats = reinterpret_cast<const pool::CompressedSplat*>(
        payload +
        pool::brick_splats_offset(h.node_count, h.leaf_count, h.splat_count, h.encoded_count, direct));
    return src;
}

/// Opens resident brick b alone (host tools: leaf bounds of a brick): its splat source and octree
/// view (without leaf bounds: a brick's are BrickLeafBounds). False when b is out of range or not
/// resident. Tracing enters bricks through descend_bricked instead.
PRT_HD PRT_INLINE bool open_brick(const BrickView& v, std::uint32_t b, BrickSplats& src, OctreeView& brick) {
    if (b >= v.brick_count) return false;
    const unsigned char* payload = brick_payload(v, b);
    if (payload == nullptr) return false;
    src = brick_splats(payload);
    brick = brick_octree(v.table[b], src.header, payload);
    return true;
}

/// A ray's footprint for level of detail, in the model's local units: width(t) = width + spread * t
/// (the renderer: 0 and RenderParams::lod_spread, render.h). 0, 0: no stop.
struct LodCone {
    float width = 0.0f;
    float spread = 0.0f;
};

/// The level at which a descent stops for footprint `f` (in units of the root cube): the shallowest
/// level whose cell size 2^-level is <= f, from f's exponent bits (exact, host and device alike);
/// k_no_lod_stop for f <= 0 or not finite.
inline constexpr std::uint32_t k_no_lod_stop = 0xffu;
PRT_HD PRT_INLINE std::uint32_t lod_stop_level(float f) {
    if (!(f > 0.0f)) return k_no_lod_stop;
#if PRT_DEVICE_CODE
    const std::uint32_t bits = __float_as_uint(f);
#else
    std::uint32_t bits;
    __builtin_memcpy(&bits, &f, sizeof(bits));
#endif
    const std::uint32_t e = (bits >> 23) & 0xffu;  // f = 1.m * 2^(e - 127) = 0.1m * 2^(e - 126)
    if (e == 0u) return k_no_lod_stop;             // subnormal: far below any cell
    return e >= 127u ? 0u : 127u - e;              // 2^-l <= f  <=>  l >= 127 - e
}

/// Where a walk through a bricked tree is (descend_bricked): in the top tree (level k_top_tree) or
/// inside brick `brick`, whose root is at `level`: the walk's path entries below that level index
/// the brick's nodes, the entry at it the top tree's brick node. Inside a resident brick the walk
/// reads its payload (whose first nodes are the LOD prefix), inside one that is not resident its
/// resident LOD prefix (payload null). What the walk needs of the brick at each descent and each
/// leaf (its node count, its leaf count, where its leaf bounds start) is read once, when the walk
/// enters it, so a descent or a leaf inside a brick reads no header. After each descent, `stop`
/// says whether the walk ended at a disc instead of a leaf (and `request` whether for want of the
/// brick).
struct BrickCursor {
    static constexpr std::uint32_t k_top_tree = 0xffffffffu;
    enum Stop : std::uint32_t { k_none = 0, k_top_disc = 1, k_prefix_disc = 2 };
    std::uint32_t level = k_top_tree;
    std::uint32_t brick = 0;
    const unsigned char* payload = nullptr;      ///< the brick's payload, null when it is not resident
    std::uint32_t lod_first = 0, lod_count = 0;  ///< the brick's prefix in lod_nodes (count 0: none)
    std::uint32_t node_count = 0;    ///< nodes walked in the brick: the payload's, else the prefix's
    std::uint32_t leaf_count = 0;    ///< the resident brick's filled leaves (0 when not resident)
    std::uint32_t bounds_first = 0;  ///< the brick's first BrickLeafBounds in the view's leaf_bounds
    std::uint32_t stop = k_none;
    std::uint32_t stop_node = 0;  ///< top node (k_top_disc) or index into lod_nodes (k_prefix_disc)
    bool request = false;
    /// The descent ended in a resident brick where its payload is needed (a filled leaf, or a node
    /// below its prefix): where the walk would have requested the brick were it missing.
    bool needs_payload = false;
    /// The ray has met a missing brick's disc: streaming flags (requests, used) are set up to the
    /// first missing brick on a ray's way only (stopped_at_disc).
    bool fell_back = false;
};

/// The node words of the cursor's brick: its payload's, or its resident prefix's when it is not
/// resident.
PRT_HD PRT_INLINE const std::uint32_t* brick_cursor_nodes(const BrickView& v, const BrickCursor& cur) {
    return cur.payload != nullptr
               ? reinterpret_cast<const std::uint32_t*>(cur.payload + pool::brick_nodes_offset())
               : v.lod_nodes + cur.lod_first;
}

/// enter_brick with streamed prefixes (BrickView::prefix_first): the cursor's prefix, flagged used,
/// or false when it is missing. Out of line: the in-core walk's registers are not spent on it.
PRT_HD PRT_NOINLINE inline bool enter_streamed_prefix(const BrickView& v, std::uint32_t b, BrickCursor& cur) {
    const std::uint32_t first = v.prefix_first[b];
    if (first == k_prefix_missing) return false;
    cur.lod_first = first;
    cur.lod_count = v.lod_nodes[first - 1];  // the whole prefix or its coarse part
    if (v.prefix_used != nullptr && !cur.fell_back) flag_brick(v.prefix_used, b);
    return true;
}

/// The walk enters brick b (brick node at `level`): the cursor's brick state, read once. False
/// when the brick is not resident and has no prefix, or its streamed prefix is missing (the walk
/// then stops at its top-node disc and requests it).
PRT_HD PRT_INLINE bool enter_brick(const BrickView& v, std::uint32_t b, std::uint32_t level,
                                   BrickCursor& cur) {
    cur.brick = b;
    cur.lod_first = cur.lod_count = 0;
    if (v.lod_table != nullptr) {
        if (v.prefix_first == nullptr) {
            cur.lod_first = static_cast<std::uint32_t>(v.lod_table[b].first);
            cur.lod_count = v.lod_table[b].node_count;
        } else if (!enter_streamed_prefix(v, b, cur)) {
            return false;  // its prefix is missing, so is its payload: the brick's top-node disc
        }
    }
    const unsigned char* payload = brick_payload(v, b);
    cur.payload = payload;
    if (payload != nullptr) {  // resident: its payload (its first nodes are the prefix)
        const auto* h = reinterpret_cast<const pool::BrickHeader*>(payload);
        cur.node_count = h->node_count;
        cur.leaf_count = h->leaf_count;
        cur.bounds_first = v.leaf_bounds_first != nullptr ? v.leaf_bounds_first[b] : 0u;
    } else {  // not resident: its resident prefix, if any
        if (cur.lod_count == 0) return false;
        cur.node_count = cur.lod_count;
        cur.leaf_count = 0;
    }
    cur.level = level;
    return true;
}

/// thesis 2.2.2 over a bricked tree, with the level-of-detail stop: descends from path[level] to the
/// leaf holding `p`, entering a brick at its brick node (its payload when resident, else its LOD
/// prefix, ending at the prefix node below which the payload is needed) and leaving it when the
/// walk's restart level is above the brick's root. At levels >= `stop_level` the first node
/// with a disc ends the descent (cur.stop). Returns the node word where it ended: a filled or empty
/// leaf (in the cursor's brick for a filled one), or the node of the disc (cur.stop set). Corrupt
/// addresses end in an empty leaf, as descend does.
///
/// One loop body for the top tree, a resident brick and a missing brick's prefix (what differs is
/// which node words, how many, and how many of them have discs), so the rays of a warp that walk in
/// different places run the same instructions per level; entering a brick is the one other case.
/// Written as the float descent's inner loop with the exits sorted out after it, it ran primary rays
/// 1-3 % faster on an H200 but shadow rays 25-28 % slower, with fewer instructions and more stalls
/// (preprocess/bench/results/h200-2026-11-28-issue17-walk, w4: variant A).
PRT_HD PRT_INLINE std::uint32_t descend_bricked(const BrickView& v, const Fixed3& p, std::uint32_t* path,
                                                std::uint32_t& level, BrickCursor& cur,
                                                std::uint32_t stop_level = k_no_lod_stop) {
    std::uint32_t l = level;
    cur.stop = BrickCursor::k_none;
    cur.request = false;
    cur.needs_payload = false;
    if (l < cur.level) cur.level = BrickCursor::k_top_tree;  // the next cell is outside the brick
    bool in_brick = cur.level != BrickCursor::k_top_tree;
    // The nodes walked, how many, the first `with_disc` of them having a disc (a stop may end
    // there: every top node when the pool has lod_splats, a brick's prefix), and lod_base + index
    // the disc of node index.
    const std::uint32_t* nodes = v.top_nodes;
    std::uint32_t count = v.top_node_count;
    std::uint32_t with_disc = v.lod != nullptr ? count : 0u;
    std::uint32_t lod_base = 0;
    // in a prefix without its payload: the payload is needed below the prefix and at filled leaves
    bool prefix_only = false;
    const auto walk_in_brick = [&] {  // the cursor's brick's nodes
        nodes = brick_cursor_nodes(v, cur);
        count = cur.node_count;
        with_disc = cur.lod_count;
        lod_base = cur.lod_first;
        prefix_only = cur.payload == nullptr;
    };
    if (in_brick) walk_in_brick();
    std::uint32_t index = in_brick && l == cur.level ? 0u : path[l];
    std::uint32_t node = load_node_word(nodes, index);
    // bounded: each pass goes one level down (l < k_fixed_bits) or enters a brick (then its nodes) once
    for (;;) {
        // The level-of-detail stop: the first node no wider than the footprint that has a disc and
        // is not empty (an inner node, a brick node of the top tree, a filled leaf of a prefix: a
        // streamed view then needs no payload where the prefix reaches the footprint's level).
        if (l >= stop_level && index < with_disc &&
            (node >> pool::k_node_address_bits) != static_cast<std::uint32_t>(pool::NodeType::empty_leaf)) {
            cur.stop = in_brick ? BrickCursor::k_prefix_disc : BrickCursor::k_top_disc;
            cur.stop_node = lod_base + index;
            break;
        }
        if (node_is_internal(node)) {
            const std::uint32_t addr = node_addr(node);
            if (l >= k_fixed_bits) return level = l, k_empty_leaf_node;
            if (addr >= count || count - addr < 8u) {
                if (!prefix_only) return level = l, k_empty_leaf_node;  // a corrupt address
                cur.request = true;  // the payload is needed below this node: this node's disc
                cur.stop = BrickCursor::k_prefix_disc;
                cur.stop_node = lod_base + index;
                break;
            }
            const std::uint32_t shift = k_fixed_bits - 1u - l;
            const std::uint32_t c =
                ((p.x >> shift) & 1u) | (((p.y >> shift) & 1u) << 1) | (((p.z >> shift) & 1u) << 2);
            index = addr + c;
            path[++l] = index;
            node = load_node_word(nodes, index);
            continue;
        }
        if (!in_brick && node_is_brick(node)) {
            const std::uint32_t b = node_addr(node);
            if (b >= v.brick_count) return level = l, k_empty_leaf_node;
            if (!enter_brick(v, b, l, cur)) {  // not resident, no prefix: the brick's top-node disc
                cur.request = true;
                cur.stop = BrickCursor::k_top_disc;
                cur.stop_node = index;
                break;
            }
            in_brick = true;
            walk_in_brick();
            index = 0;
            node = load_node_word(nodes, 0);
            continue;
        }
        if (prefix_only && node_is_filled(node)) {  // a filled leaf of a missing brick: its disc
            cur.request = true;
            cur.stop = BrickCursor::k_prefix_disc;
            cur.stop_node = lod_base + index;
        } else if (v.used != nullptr && in_brick && cur.payload != nullptr &&
                   (node_is_filled(node) || index >= with_disc)) {
            cur.needs_payload = true;  // where a missing brick's walk would have asked for it
        }
        break;  // a leaf (an empty top node, an empty or filled leaf of a brick)
    }
    level = l;
    return node;
}

/// The prefix disc a descent stopped at in a streamed prefix (its discs follow its node words). Out
/// of line, as enter_streamed_prefix.
PRT_HD PRT_NOINLINE inline pool::CompressedSplat streamed_prefix_disc(const BrickView& v,
                                                                      const BrickCursor& cur) {
    return reinterpret_cast<const pool::CompressedSplat*>(v.lod_nodes + cur.lod_first +
                                                          cur.lod_count)[cur.stop_node - cur.lod_first];
}

/// The disc a descent stopped at (cur.stop) as a one-splat source (its colour rounded to RGB565, as
/// a brick's); false for an empty node's disc.
PRT_HD PRT_INLINE bool stop_disc(const BrickView& v, const BrickCursor& cur, LodSplats& out) {
    if (cur.stop == BrickCursor::k_top_disc) {
        if (v.lod == nullptr || cur.stop_node >= v.top_node_count) return false;
        const pool::LodSplat l = v.lod[cur.stop_node];
        if (!(l.radius > 0.0f)) return false;
        out.disc = pool::Splat{l.position, l.radius, l.normal, pool::encode_rgb565(l.color)};
        return true;
    }
    pool::CompressedSplat c;
    if (v.prefix_first == nullptr) {
        if (cur.stop_node >= v.lod_node_count) return false;
        c = v.lod_discs[cur.stop_node];
    } else {
        c = streamed_prefix_disc(v, cur);
    }
    if ((c.nr >> 20) == 0u) return false;
    const pool::DecodedSplat d = pool::decode_lod_disc(c, v.lod_table[cur.brick]);
    out.disc = pool::Splat{d.position, d.radius, d.normal, c.color};
    return true;
}

/// thesis 2.2.1 over a bricked tree: the next leaf (or LOD stop) along the walk (walk_next with
/// descend_bricked), the stop level from the footprint where the walk enters the next cell.
PRT_HD PRT_INLINE bool walk_next_bricked(const BrickView& v, OctreeWalk& w, BrickCursor& cur,
                                         const LodCone& cone, OctreeLeaf& leaf) {
    return walk_step(w, leaf, [&](std::uint32_t& level) {
        return descend_bricked(v, w.p, w.path, level, cur, lod_stop_level(cone.width + cone.spread * w.t));
    });
}

/// The reference range [begin, end) of filled leaf `node` of the cursor's (resident) brick, or,
/// with the view's leaf bounds and `culling`, false when its bounds rule out a hit in [lo, hi]
/// (counted as culled) or it is empty; as next_leaf does it on the float path (splat.h). The
/// compact bounds hold no range: a leaf they keep reads its range from the brick's leaf_info (a
/// validated payload's: monotone, ending at its reference count, so no clamp). Reads no brick
/// header: the cursor holds what it needs (enter_brick).
PRT_HD PRT_INLINE bool brick_leaf_range(const BrickView& v, const BrickCursor& cur, std::uint32_t node,
                                        std::uint32_t culling, Vec3 o, Vec3 d, float inv_dlen, bool inside,
                                        float lo, float hi, std::uint32_t& begin, std::uint32_t& end,
                                        WalkStats& stats) {
    const std::uint32_t a = node_addr(node);
    if (a >= cur.leaf_count) return false;
    if (culling != k_cull_none && v.leaf_bounds != nullptr) {
        const BrickLeafBounds b = load_brick_leaf_bounds(v.leaf_bounds + cur.bounds_first + a);
        if (!brick_leaf_may_hit(b, o, d, inv_dlen, inside, lo, hi, culling)) {
            PRT_COUNT(stats.culled);
            return false;
        }
    }
    const std::uint32_t* info =
        reinterpret_cast<const std::uint32_t*>(cur.payload + pool::brick_leaf_info_offset(cur.node_count));
    begin = info[a];
    end = info[a + 1];
    return begin < end;
}

/// A disc the walk stopped at (LOD stop, or a missing brick): its hits are accepted inside the
/// stopping node's cell only, [max(t0, lo), min(t1, hi)], so neighbouring discs never stack.
/// Streaming: a ray requests the first missing brick on its way only, and keeps (flags used) no
/// brick past it: up to there its walk is the in-core walk, past it the walk goes on behind a disc
/// that stands in for the brick's splats, so what it meets there may not be what the in-core
/// image needs. A view's requests and used bricks are so a part of what its in-core render needs,
/// and a budget that holds that converges (a stalled view, counting the bricks seen through its
/// stand-in discs, asked for more than it needed). Later frames, the brick resident, go further.
PRT_HD PRT_INLINE bool stopped_at_disc(const BrickView& v, BrickCursor& cur, WalkStats& stats,
                                       LodSplats& disc) {
    if (cur.request) {
        ++stats.fallbacks;
        if (!cur.fell_back && v.requests != nullptr) flag_brick(v.requests, cur.brick);
        cur.fell_back = true;
    }
    return stop_disc(v, cur, disc);
}

/// A leaf the walk reads (after the blend window's test, as a missing brick's disc is met):
/// streaming keeps (flags used) a resident brick whose payload it needs, up to the first missing
/// brick on the ray's way, exactly where a missing brick's walk requests it (stopped_at_disc). A
/// walk that stays in a brick's prefix (a LOD stop, an empty prefix leaf) does not keep it.
PRT_HD PRT_INLINE void note_payload_use(const BrickView& v, const BrickCursor& cur) {
    if (v.used != nullptr && cur.needs_payload && !cur.fell_back) flag_brick(v.used, cur.brick);
}

/// Closest hit of a ray with a bricked model's splats (model local frame; d need not be unit), as
/// closest_hit_splats does it over the float octree: t in [0, t_max), the same blending, the same
/// leaves visited, but where the descent stops at a disc (level of detail: `cone`; or a brick that
/// is not resident), which is met as one splat inside its node's cell. Returns false on a miss.
PRT_HD inline bool closest_hit_bricks(const BrickView& v, Vec3 o, Vec3 d, bool inside, float t_max,
                                      const BlendOptions& blend, std::uint32_t max_steps, SplatSample& out,
                                      WalkStats& stats, std::uint32_t culling = k_cull_slabs,
                                      LodCone cone = {}) {
    const OctreeView top = brick_top_octree(v);
    OctreeWalk walk;
    if (!walk_begin(top, o, d, 0.0f, t_max, max_steps, walk)) return false;
    // Without the flag (prt-octree --no-replicate) each disk is in one leaf only: hits from t = 0.
    const bool replicated = (v.flags & pool::k_bricks_replicated) != 0;
    const float inv_dlen = 1.0f / length(d);
    cone.width *= v.inv_root_size;  // in units of the root cube, as the walk's cells
    cone.spread *= v.inv_root_size;
    detail::NearestHit h;
    BrickCursor cur;
    OctreeLeaf leaf;
    while (walk_next_bricked(v, walk, cur, cone, leaf)) {  // bounded by max_steps
        PRT_COUNT(stats.leaves);
        if (h.found && leaf.t0 > h.window_end) break;
        const float hi = fminf(leaf.t1, t_max);
        if (cur.stop != BrickCursor::k_none) {
            LodSplats disc;
            if (stopped_at_disc(v, cur, stats, disc) &&
                detail::closest_in_leaf(disc, 0, 1, o, d, inside, inv_dlen, leaf.t0, hi, blend, h, stats))
                break;
            continue;
        }
        note_payload_use(v, cur);
        if (!node_is_filled(leaf.node) || cur.level == BrickCursor::k_top_tree) continue;
        const float lo = replicated ? leaf.t0 : 0.0f;
        std::uint32_t begin = 0, end = 0;
        if (!brick_leaf_range(v, cur, leaf.node, culling, o, d, inv_dlen, inside,
                              fmaxf(lo, h.found ? h.t_near : 0.0f), fminf(hi, h.found ? h.window_end : k_inf),
                              begin, end, stats))
            continue;
        const BrickSplats src = brick_splats(cur.payload);  // the header, for a leaf whose splats are read
        if (detail::closest_in_leaf(src, begin, end, o, d, inside, inv_dlen, lo, hi, blend, h, stats)) break;
    }
    if (walk.truncated) ++stats.truncated;
    return detail::finish_nearest(Rgb565Splats{}, h, out);
}

/// Any hit of a ray with a bricked model's splats in t in [0, t_max) (shadow rays, thesis 5.2), as
/// any_hit_splats does it over the float octree, with the same discs as closest_hit_bricks.
PRT_HD inline bool any_hit_bricks(const BrickView& v, Vec3 o, Vec3 d, bool inside, float t_max,
                                  std::uint32_t max_steps, WalkStats& stats,
                                  std::uint32_t culling = k_cull_slabs, LodCone cone = {}) {
    const OctreeView top = brick_top_octree(v);
    OctreeWalk walk;
    if (!walk_begin(top, o, d, 0.0f, t_max, max_steps, walk)) return false;
    const float hi = next_toward_zero(t_max);
    const float inv_dlen = 1.0f / length(d);
    cone.width *= v.inv_root_size;
    cone.spread *= v.inv_root_size;
    // as any_hit_splats: a fully replicated, unculled tree passes a leaf by its own t range
    const bool own_range =
        (v.flags & pool::k_bricks_replicated) != 0 && (v.flags & pool::k_bricks_culled) == 0;
    BrickCursor cur;
    OctreeLeaf leaf;
    while (walk_next_bricked(v, walk, cur, cone, leaf)) {  // bounded by max_steps
        PRT_COUNT(stats.leaves);
        if (cur.stop != BrickCursor::k_none) {
            LodSplats disc;
            if (stopped_at_disc(v, cur, stats, disc) &&
                detail::any_in_leaf(disc, 0, 1, o, d, inside, leaf.t0, fminf(leaf.t1, hi), stats))
                return true;
            continue;
        }
        note_payload_use(v, cur);
        if (!node_is_filled(leaf.node) || cur.level == BrickCursor::k_top_tree) continue;
        std::uint32_t begin = 0, end = 0;
        if (!brick_leaf_range(v, cur, leaf.node, culling, o, d, inv_dlen, inside, own_range ? leaf.t0 : 0.0f,
                              own_range ? fminf(leaf.t1, hi) : hi, begin, end, stats))
            continue;
        const BrickSplats src = brick_splats(cur.payload);
        if (detail::any_in_leaf(src, begin, end, o, d, inside, 0.0f, hi, stats)) return true;
    }
    if (walk.truncated) ++stats.truncated;
    return false;
}

}  // namespace prt::core
