// PointRT pool file: the brick sections (types 128-132, brick_layout.h, written by prt-bricks,
// issue 17) of an opened pool, validated into typed views (formats/POOL.md, "Bricks and level of
// detail"). validate_brick_index checks everything but the bricks' payloads (what a streaming reader
// keeps resident); validate_brick checks one brick's payload alone, as read or uploaded. Host only.
#pragma once

#include <cstdint>
#include <span>

#include "prt/formats/brick_layout.h"
#include "prt/formats/pool.h"

namespace prt::pool {

/// The brick sections of a pool: views into the mapped file, valid while the PoolFile lives.
struct BrickSections {
    BrickInfo info{};
    std::span<const std::uint32_t> top_nodes;    ///< info.top_node_count node words, node 0 the root
    std::span<const BrickEntry> table;           ///< info.brick_count entries
    std::span<const std::byte> data;             ///< brick_data: every brick's payload
    std::span<const LodSplat> lod;               ///< one per top node (parallel to top_nodes)
    std::span<const BrickLod> lod_table;         ///< per brick, or empty (no LOD prefixes)
    std::span<const std::uint32_t> lod_nodes;    ///< the bricks' LOD prefix node words
    std::span<const CompressedSplat> lod_discs;  ///< parallel to lod_nodes

    /// Brick b's LOD prefix node words (empty without LOD prefixes).
    std::span<const std::uint32_t> lod_prefix(std::uint32_t b) const {
        if (lod_table.empty()) return {};
        return lod_nodes.subspan(static_cast<std::size_t>(lod_table[b].first), lod_table[b].node_count);
    }

    /// The payload bytes of brick `b` (entry's offset and size; checked by validate_brick_index).
    std::span<const std::byte> payload(std::uint32_t b) const {
        return data.subspan(static_cast<std::size_t>(table[b].offset),
                            static_cast<std::size_t>(table[b].size));
    }
};

/// Typed views into one brick payload (layout in brick_layout.h); the payload must be validated.
struct BrickView {
    const BrickHeader* header = nullptr;
    std::span<const std::uint32_t> nodes;      ///< the brick's subtree, node 0 its root
    std::span<const std::uint32_t> leaf_info;  ///< leaf_count + 1 begin indices into the references
    const std::byte* refs = nullptr;           ///< splat_count references, ref_bytes each; null: direct
    std::uint32_t ref_bytes = 2;               ///< 2, 4, or 0 in a direct brick
    std::span<const CompressedSplat> splats;   ///< encoded_count compressed splats

    /// Reference i: the index among `splats` of the leaves' i-th splat (i itself in a direct brick).
    std::uint32_t ref(std::size_t i) const {
        if (ref_bytes == 0) return static_cast<std::uint32_t>(i);
        if (ref_bytes == 2) return reinterpret_cast<const std::uint16_t*>(refs)[i];
        return reinterpret_cast<const std::uint32_t*>(refs)[i];
    }
};
BrickView brick_view(std::span<const std::byte> payload);

/// Whether the pool holds any of the brick sections (128-134).
bool has_bricks(const PoolFile& pool);

/// Validates the brick sections except the bricks' payloads: all five present together, exactly
/// one BrickInfo with a finite root cube, counts as brick_info says (a pool claiming more bricks
/// than its table holds is refused), the top tree a proper tree from node 0 (children after their
/// parent, every node reached once, no filled leaf, at most brick_info.depth levels) whose brick
/// nodes address every brick exactly once, each entry naming that node, its level and cube; the
/// table's payloads 64-byte aligned, inside brick_data and not overlapping, of the size their counts
/// give; splat counts adding up to brick_info's; LOD discs finite; the index layout flag set (bricks
/// of an older prt-bricks are refused: write them again); the optional LOD prefixes (brick_lod,
/// lod_nodes and lod_discs together, as the k_bricks_lod flag says): one per brick inside lod_nodes, of 1 to
/// the brick's node count nodes, a finite cube and an exponent in range, node words addressing the brick's
/// nodes (children after their parent) and leaves, disc normal codes in range. Throws prt::Error "FILE:
/// section NAME: [brick I: ]what is wrong".
BrickSections validate_brick_index(const PoolFile& pool);

/// Validates one brick alone (streaming: a brick read or uploaded by itself): `payload` holds the
/// entry's `size` bytes; its XXH3-64 checksum, header counts equal to the entry's, a finite positive
/// quantization cube, the radius exponent in range, its nodes a proper tree of at most
/// info.depth - entry.level levels whose filled leaves address leaf_info exactly once, leaf_info
/// monotone and covering the references exactly, every reference naming an encoded splat and every
/// encoded splat referenced, every octahedral code in range; its LOD prefix (if any) the copy of its
/// first nodes, with its quantization cube. Throws prt::Error
/// "FILE: section brick_data: brick I: what is wrong".
void validate_brick(const PoolFile& pool, const BrickSections& sections, std::uint32_t index,
                    std::span<const std::byte> payload);

/// validate_brick_index, then validate_brick on every brick.
BrickSections validate_bricks(const PoolFile& pool);

}  // namespace prt::pool
