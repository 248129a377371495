// PointRT pool file: checks the section validators share (formats/POOL.md, "Validation"). Internal
// to formats/src; every failure is PoolFile::fail's one line "FILE: section NAME: what is wrong".
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "prt/formats/pool.h"

namespace prt::pool::detail {

/// The entry of the first of `types` the pool holds, or nullptr when it holds none.
const SectionEntry* first_present(const PoolFile& pool, std::span<const SectionType> types);

/// Fails unless the pool holds every section of `required` (a prefix of `family`, the sections one
/// validator reads): on the first of `family` present with `needs`, or, when the pool holds none of
/// them, with "no WHAT sections (run TOOL)", TOOL the writer of family[0].
void require_sections(const PoolFile& pool, std::span<const SectionType> family, std::size_t required,
                      const char* needs, const char* what);

/// The element of a section that must hold exactly one ("must hold exactly one element").
template <class T>
const T& single(const PoolFile& pool, SectionType type) {
    const std::span<const T> elements = pool.array<T>(type);
    if (elements.size() != 1) pool.fail(pool.find(type), "must hold exactly one element");
    return elements[0];
}

/// Fails on `entry` with "HAVE WHAT but INFO says WANT" unless have == want.
void check_count(const PoolFile& pool, const SectionEntry* entry, std::uint64_t have, std::uint64_t want,
                 const char* what, const char* info);

/// Whether a box is finite and not inverted on any axis.
bool finite_box(const float lo[3], const float hi[3]);

/// Checks node words in the splat octree's encoding (pool_layout.h) for a proper tree from node 0:
/// every child group after its parent and inside the array, every node reached exactly once, no
/// type but internal, empty and `leaf_type`, no internal node at `max_level` or deeper, every filled leaf
/// addressing a distinct leaf below `leaf_count` and every leaf addressed; with `leaves_at_max_level`, every
/// filled leaf at `max_level` (<= 255). `nodes` must not be empty. Returns the deepest filled leaf's level (0
/// when there is none). Errors name `entry`, the nodes section, then `where` (e.g. "brick 17: "). `leaf_type`
/// is the type whose address indexes the leaves: NodeType::brick for the top tree of a bricked pool
/// (brick_top_nodes), whose "leaves" are bricks and which holds no filled leaf.
std::uint32_t check_node_tree(const PoolFile& pool, const SectionEntry* entry,
                              std::span<const std::uint32_t> nodes, std::uint32_t leaf_count,
                              std::uint32_t max_level, bool leaves_at_max_level,
                              const std::string& where = "", NodeType leaf_type = NodeType::filled_leaf);

/// POOL.md Validation step 4, the splat octree: the four sections together, counts as octree_info
/// says, internal nodes pointing forward to eight children in range, filled leaves addressing
/// leaf_info in range, leaf_info monotone and covering splats exactly, every splat's point in range
/// (`info`: the pool's model_info). PoolFile::open runs it; prt/formats/octree_sections.h reads the
/// checked sections.
void check_splat_octree(const PoolFile& pool, const ModelInfo& info);

}  // namespace prt::pool::detail
