// PointRT pool file: bricks, compressed splats and level of detail (types 128-143, written by
// prt-bricks, issue 17; formats/POOL.md "Bricks and level of detail"). Plain structs and PRT_HD
// inline codec functions: this header compiles under g++ and nvcc, so the traversal decodes splats
// on the fly from the mapped (or uploaded) brick payloads.
//
//   brick_info (128)       one BrickInfo (64 B): root cube, depth, counts, the cut's splat bound
//   brick_top_nodes (129)  uint32 node words of the resident top tree, the splat octree's encoding
//                          (pool_layout.h) with NodeType::brick: address = brick index
//   brick_table (130)      BrickEntry[brick_count] (64 B): cube, payload offset/size, counts,
//                          level, top node, XXH3-64 of the payload
//   brick_data (131)       bytes; brick b at brick_table[b].offset (a multiple of 64):
//                            BrickHeader (48 B)   quantization cube, counts, radius exponent
//                            uint32 nodes[node_count]        the brick's subtree, addresses
//                                                            relative to the brick (node 0 = root)
//                            uint32 leaf_info[leaf_count + 1] begin indices into the references
//                            refs[splat_count]    per leaf, in leaf order: the index of each of its
//                                                 splats among the brick's encoded splats; uint16
//                                                 when encoded_count <= 65536, else uint32;
//                                                 zero-padded to a multiple of 4 bytes
//                                                 (absent in a direct brick, below)
//                            CompressedSplat splats[encoded_count]   12 B each: each splat once,
//                                                 however many leaves of the brick hold it
//                          A direct brick (BrickHeader::layout = k_brick_direct) has no refs: its
//                          leaves' splats are stored in leaf order, a replica once per leaf that
//                          holds it (encoded_count = splat_count, splat i of the leaves is
//                          splats[i]), so a splat test reads one record instead of a reference and
//                          then its record. prt-bricks writes a brick direct when that takes no
//                          more bytes (little replication: culled pools); the entry's size tells
//                          the two layouts apart without the payload.
//   lod_splats (132)       LodSplat[top node count] (32 B), parallel to brick_top_nodes: the
//                          representative disc of top node i (radius 0 for an empty leaf)
//   brick_lod (133)        optional, with lod_nodes and lod_discs: BrickLod[brick_count] (32 B):
//                          brick b's level-of-detail prefix: its first node_count nodes (breadth
//                          first: the brick's top levels) at lod_nodes[first..], and the cube and
//                          radius exponent their discs decode with
//   lod_nodes (134)        uint32: copies of the prefix nodes' words (addresses relative to the brick)
//   lod_discs (135)        CompressedSplat (12 B), parallel to lod_nodes: the disc of the node's
//                          subtree (radius code 0: an empty node): centre = area-weighted mean of
//                          the centres of the points whose centre cell is in the subtree, normal and
//                          colour their area-weighted means, radius covering every splat disc of the
//                          subtree. Resident with the top tree, so a ray stops at a node whose
//                          footprint is below a pixel (bricks.h) with no brick data, and the far
//                          parts of a view need no brick.
//
// CompressedSplat (12 bytes, little-endian):
//   +0  uint16 q[3]       position: quant_min + q * quant_size / 65535 per axis (round to nearest)
//   +6  uint16 color      RGB565: r bits 15-11, g bits 10-5, b bits 4-0 (white without colors)
//   +8  uint32 nr         bits 0-9 octahedral u, bits 10-19 octahedral v (0..1022, 511 = 0),
//                         bits 20-31 radius code c: 0 = radius 0, else
//                         quant_size * 2^(radius_log2_min + (c - 1) / 128), never below the float
//                         radius (encode rounds up, with a 2^-20 relative margin for device exp2f)
// Not carried: the source point index (colors travel in the splat; material_ids and intensities
// are not in bricks, prt-bricks reports what a pool loses).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "prt/formats/pool_layout.h"

/// The codec below is called from the core's kernels too (this header does not see
/// prt/core/config.h): host + device under nvcc.
#if defined(__CUDACC__)
#define PRT_BRICK_HD __host__ __device__
#else
#define PRT_BRICK_HD
#endif

namespace prt::pool {

/// Every brick payload starts on this boundary inside brick_data.
inline constexpr std::uint64_t k_brick_alignment = 64;
/// A payload's `size` rounded up to k_brick_alignment: the bytes it takes in brick_data.
constexpr std::uint64_t brick_padded_size(std::uint64_t size) {
    return (size + k_brick_alignment - 1) / k_brick_alignment * k_brick_alignment;
}
/// Octahedral normal levels per axis: codes 0..1022, 511 is exactly 0 (so +-z and the folds are exact).
inline constexpr std::uint32_t k_oct_max_code = 1022;
inline constexpr float k_oct_half = 511.0f;
/// Radius codes per octave and the largest code (12 bits): 4094 / 128 ~ 32 octaves of range.
inline constexpr float k_radius_steps_per_octave = 128.0f;
inline constexpr std::uint32_t k_radius_max_code = 4095;
/// Position levels per axis (16 bits).
inline constexpr float k_position_max_code = 65535.0f;
/// Relative margin an encoded radius keeps above the float radius (device exp2f is 2 ulp).
inline constexpr float k_radius_margin = 1.0f / 1048576.0f;
/// Range a valid brick's radius exponent lies in.
inline constexpr std::int32_t k_radius_log2_limit = 160;

/// Bricked-pool facts (section brick_info, exactly one element).
struct BrickInfo {
    float root_min[3];                ///< 0: root cube of the whole tree, local frame (as octree_info)
    float root_size;                  ///< 12
    std::uint32_t depth;              ///< 16: deepest level of the whole tree (root = 0)
    std::uint32_t brick_count;        ///< 20: elements of brick_table
    std::uint32_t top_node_count;     ///< 24: elements of brick_top_nodes and lod_splats
    std::uint32_t brick_splat_limit;  ///< 28: N of the cut: a node holding <= N splats is a brick
    std::uint32_t max_brick_splats;   ///< 32: most splats in one brick (> N only for one huge leaf)
    std::uint32_t flags;              ///< 36: BrickFlags
    std::uint64_t splat_count;        ///< 40: splats in all bricks (replicas included)
    std::uint64_t unique_splats;      ///< 48: as OctreeInfo::unique_splats
    std::uint64_t encoded_splats;     ///< 56: compressed splats in all bricks (each once per brick)
};
static_assert(sizeof(BrickInfo) == 64);
static_assert(offsetof(BrickInfo, depth) == 16);
static_assert(offsetof(BrickInfo, flags) == 36);
static_assert(offsetof(BrickInfo, splat_count) == 40);
static_assert(offsetof(BrickInfo, encoded_splats) == 56);

/// BrickInfo::flags bits.
enum BrickFlags : std::uint32_t {
    k_bricks_colors = 1u << 0,      ///< splat colours come from the model's colors (else white)
    k_bricks_float_kept = 1u << 1,  ///< the float octree sections (16-19) were kept beside the bricks
    k_bricks_culled = 1u << 2,      ///< the source octree was culled (prt-cull)
    k_bricks_replicated = 1u << 3,  ///< the source octree was replicated (prt-octree; else --no-replicate)
    /// Leaves reference their splats by index (the layout above). Required: bricks written before
    /// the index (a splat copied into every leaf) are refused, prt-bricks writes them again.
    k_bricks_indexed = 1u << 4,
    /// The optional sections brick_lod, lod_nodes and lod_discs are present (prt-bricks --lod-splats).
    k_bricks_lod = 1u << 5,
};

/// One brick (section brick_table, 64 bytes).
struct BrickEntry {
    float cube_min[3];            ///< 0: the brick root's cube, local frame
    float cube_size;              ///< 12
    std::uint64_t offset;         ///< 16: payload byte offset in brick_data (multiple of 64)
    std::uint64_t size;           ///< 24: payload bytes (brick_payload_size), padding excluded
    std::uint32_t node_count;     ///< 32: nodes of the brick's subtree
    std::uint32_t leaf_count;     ///< 36: filled leaves
    std::uint32_t splat_count;    ///< 40: splat references of its leaves (replicas included)
    std::uint32_t top_node;       ///< 44: the brick_top_nodes node that addresses this brick
    std::uint32_t level;          ///< 48: level of the brick's root (root of the whole tree = 0)
    std::uint32_t encoded_count;  ///< 52: compressed splats (each splat once)
    std::uint64_t checksum;       ///< 56: XXH3-64 of the payload's `size` bytes
};
static_assert(sizeof(BrickEntry) == 64);
static_assert(offsetof(BrickEntry, offset) == 16);
static_assert(offsetof(BrickEntry, node_count) == 32);
static_assert(offsetof(BrickEntry, level) == 48);
static_assert(offsetof(BrickEntry, checksum) == 56);

/// The first 48 bytes of a brick payload: what decoding needs, so a brick decodes alone.
struct BrickHeader {
    float quant_min[3];            ///< 0: quantization cube: the brick cube grown to hold every
    float quant_size;              ///< 12:   splat centre (replicas reach outside the cube)
    std::uint32_t node_count;      ///< 16: = BrickEntry::node_count
    std::uint32_t leaf_count;      ///< 20: = BrickEntry::leaf_count
    std::uint32_t splat_count;     ///< 24: = BrickEntry::splat_count (references)
    std::int32_t radius_log2_min;  ///< 28: exponent of radius code 1 (relative to quant_size)
    std::uint32_t encoded_count;   ///< 32: = BrickEntry::encoded_count
    std::uint32_t layout;          ///< 36: BrickLayout (0 in pools written before direct bricks)
    std::uint32_t reserved[2];     ///< 40: 0
};
static_assert(sizeof(BrickHeader) == 48);
static_assert(offsetof(BrickHeader, radius_log2_min) == 28);
static_assert(offsetof(BrickHeader, encoded_count) == 32);
static_assert(offsetof(BrickHeader, layout) == 36);

/// BrickHeader::layout: how a brick's leaves name their splats.
enum BrickLayout : std::uint32_t {
    k_brick_referenced = 0,  ///< refs[splat_count] index the distinct encoded splats
    k_brick_direct = 1,      ///< no refs: splats in leaf order, encoded_count = splat_count
};

/// A compressed splat (12 bytes; bit layout in the file comment).
struct CompressedSplat {
    std::uint16_t q[3];   ///< 0: quantized position
    std::uint16_t color;  ///< 6: RGB565
    std::uint32_t nr;     ///< 8: octahedral normal (20 bits) + radius code (12 bits)
};
static_assert(sizeof(CompressedSplat) == 12);
static_assert(offsetof(CompressedSplat, color) == 6);
static_assert(offsetof(CompressedSplat, nr) == 8);

/// The representative disc of a top-tree node (section lod_splats, 32 bytes): centre = area-weighted
/// mean of its splats' centres, normal = their area-weighted mean normal (unit; +z when they cancel),
/// radius = the largest |centre_i - centre| + radius_i (the disc's sphere holds every child disc),
/// colour = area-weighted mean. Radius 0: an empty node.
struct LodSplat {
    Float3 position;  ///< 0
    float radius;     ///< 12
    Float3 normal;    ///< 16
    Rgba8 color;      ///< 28
};
static_assert(sizeof(LodSplat) == 32);
static_assert(offsetof(LodSplat, color) == 28);

/// Brick b's level-of-detail prefix (section brick_lod, 32 bytes): the brick's nodes 0..node_count-1
/// (its top levels: bricks are numbered breadth first) are lod_nodes[first + i], their discs
/// lod_discs[first + i]. A prefix node whose
/// children lie past node_count (or a filled leaf) needs the brick's payload below it. The discs
/// decode with the brick's quantization cube (BrickHeader::quant_min/quant_size) and their own
/// radius exponent.
struct BrickLod {
    float quant_min[3];            ///< 0: = the brick's BrickHeader::quant_min
    float quant_size;              ///< 12: = BrickHeader::quant_size
    std::int32_t radius_log2_min;  ///< 16: exponent of radius code 1 of the discs
    std::uint32_t node_count;      ///< 20: nodes in the prefix (>= 1, <= the brick's node_count)
    std::uint64_t first;           ///< 24: index of the brick's first node in lod_nodes and lod_discs
};
static_assert(sizeof(BrickLod) == 32);
static_assert(offsetof(BrickLod, radius_log2_min) == 16);
static_assert(offsetof(BrickLod, first) == 24);

/// A decoded splat.
struct DecodedSplat {
    Float3 position;
    float radius;
    Float3 normal;
    Rgba8 color;
};

// ---- Payload layout -----------------------------------------------------------------------------

PRT_BRICK_HD inline constexpr std::uint64_t brick_nodes_offset() {
    return sizeof(BrickHeader);
}
PRT_BRICK_HD inline constexpr std::uint64_t brick_leaf_info_offset(std::uint32_t node_count) {
    return sizeof(BrickHeader) + 4ull * node_count;
}
/// Bytes of one splat reference in a brick of `encoded_count` compressed splats: 2 or 4.
PRT_BRICK_HD inline constexpr std::uint32_t brick_ref_bytes(std::uint32_t encoded_count) {
    return encoded_count <= 65536u ? 2u : 4u;
}
PRT_BRICK_HD inline constexpr std::uint64_t brick_refs_offset(std::uint32_t node_count,
                                                              std::uint32_t leaf_count) {
    return brick_leaf_info_offset(node_count) + 4ull * (std::uint64_t(leaf_count) + 1);
}
/// Where the compressed splats start; `direct`: a direct brick (no refs).
PRT_BRICK_HD inline constexpr std::uint64_t brick_splats_offset(std::uint32_t node_count,
                                                                std::uint32_t leaf_count,
                                                                std::uint32_t splat_count,
                                                                std::uint32_t encoded_count,
                                                                bool direct = false) {
    if (direct) return brick_refs_offset(node_count, leaf_count);
    return (brick_refs_offset(node_count, leaf_count) +
            std::uint64_t(brick_ref_bytes(encoded_count)) * splat_count + 3) /
           4 * 4;
}
/// Bytes of a brick payload with these counts (before padding to k_brick_alignment); a direct
/// brick's encoded_count equals its splat_count.
PRT_BRICK_HD inline constexpr std::uint64_t brick_payload_size(std::uint32_t node_count,
                                                               std::uint32_t leaf_count,
                                                               std::uint32_t splat_count,
                                                               std::uint32_t encoded_count,
                                                               bool direct = false) {
    return brick_splats_offset(node_count, leaf_count, splat_count, encoded_count, direct) +
           sizeof(CompressedSplat) * std::uint64_t(encoded_count);
}
/// Whether a brick of `splat_count` references to `distinct` splats takes no more bytes direct (each
/// reference its own 12-byte record) than referenced (2-4 B references + the distinct records).
PRT_BRICK_HD inline constexpr bool brick_direct_is_smaller(std::uint32_t splat_count,
                                                           std::uint32_t distinct) {
    return brick_payload_size(1, 0, splat_count, splat_count, true) <=
           brick_payload_size(1, 0, splat_count, distinct, false);
}
/// Whether a payload's header says direct.
PRT_BRICK_HD inline constexpr bool brick_is_direct(const BrickHeader& h) {
    return h.layout == k_brick_direct;
}
/// Whether a table entry is a direct brick's, from its counts and size alone (with equal counts a
/// referenced payload is larger by its references), so the index tells the layouts apart without
/// the payloads.
PRT_BRICK_HD inline constexpr bool brick_entry_is_direct(const BrickEntry& e) {
    return e.encoded_count == e.splat_count &&
           e.size == brick_payload_size(e.node_count, e.leaf_count, e.splat_count, e.encoded_count, true);
}

// ---- Codec ----------------------------------------------------------------------------------------
// Encoders run on the host (prt-bricks) in double; decoders are float, host and device.

/// Position code of one coordinate: round((x - lo) / size * 65535), clamped to [0, 65535].
/// Error of the decoded value: at most half a quantum (size / 131070) plus float rounding.
PRT_BRICK_HD inline std::uint16_t encode_coordinate(float x, float lo, float size) {
    const double t = (double(x) - double(lo)) / double(size) * double(k_position_max_code);
    // !(t > 0) also catches NaN
    const double r =
        !(t > 0) ? 0.0 : (t > double(k_position_max_code) ? double(k_position_max_code) : t + 0.5);
    return static_cast<std::uint16_t>(r);
}
PRT_BRICK_HD inline float decode_coordinate(std::uint16_t q, float lo, float size) {
    return lo + float(q) * (size / k_position_max_code);
}

/// RGB565 of an sRGB colour (round to nearest; alpha dropped). Decoded error: R, B <= 4, G <= 2.
PRT_BRICK_HD inline std::uint16_t encode_rgb565(Rgba8 c) {
    const std::uint32_t r = (std::uint32_t(c.r) * 31u + 127u) / 255u;
    const std::uint32_t g = (std::uint32_t(c.g) * 63u + 127u) / 255u;
    const std::uint32_t b = (std::uint32_t(c.b) * 31u + 127u) / 255u;
    return static_cast<std::uint16_t>((r << 11) | (g << 5) | b);
}
PRT_BRICK_HD inline Rgba8 decode_rgb565(std::uint16_t v) {
    const std::uint32_t r = (v >> 11) & 31u, g = (v >> 5) & 63u, b = v & 31u;
    return Rgba8{static_cast<std::uint8_t>((r * 255u + 15u) / 31u),
                 static_cast<std::uint8_t>((g * 255u + 31u) / 63u),
                 static_cast<std::uint8_t>((b * 255u + 15u) / 31u), 255};
}

/// float(v) - k for v < 2^23 and an integer 0 <= k < 2^23, exactly. On the GPU without a
/// conversion instruction: the float whose mantissa holds v is 2^23 + v, so one logic op and one add
/// on the FMA pipes, where float(v) - k takes an I2F on the slower conversion pipe and the same add.
PRT_BRICK_HD inline float small_uint_minus(std::uint32_t v, float k) {
#if defined(__CUDA_ARCH__)
    return __int_as_float(0x4B000000 | v) - (8388608.0f + k);
#else
    return float(v) - k;
#endif
}

/// The octahedral point of a normal code (Cigolle et al. 2014, "A Survey of Efficient
/// Representations for Independent Unit Vectors", JCGT 3(2), sec. 3.3), folded back onto the
/// octahedron |x| + |y| + |z| = k_oct_half: the normal's direction, not unit, scaled by k_oct_half
/// so that every component is a small integer, exact in float (codes 0, 511 and 1022 give -511, 0
/// and 511). The tracer tests splats with it (a ray-plane test needs neither a unit normal nor a
/// scale) and normalizes only the normals it blends (bricks.h), which saves a square root, a division
/// and the scaling per splat test.
PRT_BRICK_HD inline Float3 decode_octahedral_point(std::uint32_t code) {
    const float px = small_uint_minus(code & 1023u, k_oct_half);
    const float py = small_uint_minus((code >> 10) & 1023u, k_oct_half);
    float x = px, y = py;
    const float z = k_oct_half - fabsf(px) - fabsf(py);
    if (z < 0) {  // the lower half: folded (px = 0 is +0, so it takes the + side, as px >= 0 did)
        x = copysignf(k_oct_half - fabsf(py), px);
        y = copysignf(k_oct_half - fabsf(px), py);
    }
    return Float3{x, y, z};
}
/// An octahedral point as a unit vector.
PRT_BRICK_HD inline Float3 normalize_octahedral(Float3 p) {
    const float inv = 1.0f / sqrtf(p.x * p.x + p.y * p.y + p.z * p.z);
    return Float3{p.x * inv, p.y * inv, p.z * inv};
}
/// Decodes an octahedral normal code: unit vector.
PRT_BRICK_HD inline Float3 decode_octahedral(std::uint32_t code) {
    return normalize_octahedral(decode_octahedral_point(code));
}

/// Octahedral code (20 bits) of a unit normal: of the four codes around the projected point, the
/// one decoding closest to the normal (the survey's "precise" variant). A zero normal gives +z.
PRT_BRICK_HD inline std::uint32_t encode_octahedral(Float3 n) {
    const double l1 = fabs(double(n.x)) + fabs(double(n.y)) + fabs(double(n.z));
    if (!(l1 > 0)) return 511u | (511u << 10);
    double px = n.x / l1, py = n.y / l1;
    if (n.z < 0) {
        const double ox = px, oy = py;
        px = (1.0 - fabs(oy)) * (ox >= 0 ? 1.0 : -1.0);
        py = (1.0 - fabs(ox)) * (oy >= 0 ? 1.0 : -1.0);
    }
    const double ux = (px + 1.0) * k_oct_half, uy = (py + 1.0) * k_oct_half;
    const double bx = floor(ux), by = floor(uy);
    std::uint32_t best = 0;
    double best_dot = -2.0;
    for (int i = 0; i < 4; ++i) {
        double cx = bx + (i & 1), cy = by + (i >> 1);
        cx = cx < 0 ? 0 : (cx > k_oct_max_code ? k_oct_max_code : cx);
        cy = cy < 0 ? 0 : (cy > k_oct_max_code ? k_oct_max_code : cy);
        const std::uint32_t code = std::uint32_t(cx) | (std::uint32_t(cy) << 10);
        const Float3 d = decode_octahedral(code);
        const double dot = double(d.x) * n.x + double(d.y) * n.y + double(d.z) * n.z;
        if (dot > best_dot) best_dot = dot, best = code;
    }
    return best;
}

/// Radius of code c in a brick (0 for c = 0).
PRT_BRICK_HD inline float decode_radius(std::uint32_t c, float quant_size, std::int32_t log2_min) {
    if (c == 0) return 0.0f;
    return quant_size * exp2f(float(log2_min) + float(c - 1) / k_radius_steps_per_octave);
}

/// Radius code of r > 0: the smallest code whose radius, less k_radius_margin, is >= r (never
/// rounded down; at most one step, a factor 2^(1/128) = 1.0054, larger, unless r lies below code 1's
/// radius, which is then used). r <= 0 or not finite gives 0. Returns k_radius_max_code + 1 when r
/// exceeds the largest code (the encoder must choose log2_min so it does not).
PRT_BRICK_HD inline std::uint32_t encode_radius(float r, float quant_size, std::int32_t log2_min) {
    if (!(r > 0) || !(r < 3.0e38f)) return 0;
    const double e = (log2(double(r) / double(quant_size)) - log2_min) * k_radius_steps_per_octave;
    double c = ceil(e) + 1.0;
    if (c < 1) c = 1;
    if (c > k_radius_max_code + 1.0) return k_radius_max_code + 1;
    std::uint32_t code = std::uint32_t(c);
    while (code > 1 && decode_radius(code - 1, quant_size, log2_min) * (1.0f - k_radius_margin) >= r) --code;
    while (code <= k_radius_max_code &&
           decode_radius(code, quant_size, log2_min) * (1.0f - k_radius_margin) < r)
        ++code;
    return code;
}

/// The radius exponent a brick uses: its largest radius (relative to quant_size) gets a code
/// below the top, so every radius of the brick is representable; the 32 octaves below it too.
PRT_BRICK_HD inline std::int32_t radius_log2_min_for(float max_radius, float quant_size) {
    if (!(max_radius > 0)) return 0;
    const double l = ceil(log2(double(max_radius) / double(quant_size))) - 31.0;
    return l < -k_radius_log2_limit
               ? -k_radius_log2_limit
               : (l > k_radius_log2_limit - 32 ? k_radius_log2_limit - 32 : std::int32_t(l));
}

/// Encodes a splat in a brick: position relative to the quantization cube, normal, radius, colour.
/// Returns false when the radius does not fit the brick's exponent (nothing sensible is stored).
PRT_BRICK_HD inline bool encode_splat(const Float3& position, float radius, const Float3& normal, Rgba8 color,
                                      const BrickHeader& h, CompressedSplat* out) {
    out->q[0] = encode_coordinate(position.x, h.quant_min[0], h.quant_size);
    out->q[1] = encode_coordinate(position.y, h.quant_min[1], h.quant_size);
    out->q[2] = encode_coordinate(position.z, h.quant_min[2], h.quant_size);
    out->color = encode_rgb565(color);
    const std::uint32_t rc = encode_radius(radius, h.quant_size, h.radius_log2_min);
    out->nr = encode_octahedral(normal) | ((rc & k_radius_max_code) << 20);
    return rc <= k_radius_max_code;
}

/// Decodes a splat quantized in the cube (quant_min, quant_size) with radius exponent log2_min.
PRT_BRICK_HD inline DecodedSplat decode_splat(const CompressedSplat& s, const float quant_min[3],
                                              float quant_size, std::int32_t log2_min) {
    DecodedSplat d;
    d.position = Float3{decode_coordinate(s.q[0], quant_min[0], quant_size),
                        decode_coordinate(s.q[1], quant_min[1], quant_size),
                        decode_coordinate(s.q[2], quant_min[2], quant_size)};
    d.radius = decode_radius(s.nr >> 20, quant_size, log2_min);
    d.normal = decode_octahedral(s.nr & 0xFFFFFu);
    d.color = decode_rgb565(s.color);
    return d;
}
PRT_BRICK_HD inline DecodedSplat decode_splat(const CompressedSplat& s, const BrickHeader& h) {
    return decode_splat(s, h.quant_min, h.quant_size, h.radius_log2_min);
}
/// A level-of-detail disc of a brick's prefix.
PRT_BRICK_HD inline DecodedSplat decode_lod_disc(const CompressedSplat& s, const BrickLod& l) {
    return decode_splat(s, l.quant_min, l.quant_size, l.radius_log2_min);
}

}  // namespace prt::pool
