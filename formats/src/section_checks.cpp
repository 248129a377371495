// PointRT pool file: checks the section validators share (section_checks.h).
#include "section_checks.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace prt::pool::detail {

const SectionEntry* first_present(const PoolFile& pool, std::span<const SectionType> types) {
    for (const SectionType type : types)
        if (const SectionEntry* e = pool.find(type)) return e;
    return nullptr;
}

void require_sections(const PoolFile& pool, std::span<const SectionType> family, std::size_t required,
                      const char* needs, const char* what) {
    for (const SectionType type : family.first(required)) {
        if (pool.find(type)) continue;
        const SectionEntry* any = first_present(pool, family);
        if (any) pool.fail(any, needs);
        pool.fail(nullptr, std::string("no ") + what + " sections (run " + section_writer(family[0]) + ")");
    }
}

void check_count(const PoolFile& pool, const SectionEntry* entry, std::uint64_t have, std::uint64_t want,
                 const char* what, const char* info) {
    if (have != want)
        pool.fail(entry,
                  std::to_string(have) + " " + what + " but " + info + " says " + std::to_string(want));
}

bool finite_box(const float lo[3], const float hi[3]) {
    for (int a = 0; a < 3; ++a)
        if (!std::isfinite(lo[a]) || !std::isfinite(hi[a]) || lo[a] > hi[a]) return false;
    return true;
}

std::uint32_t check_node_tree(const PoolFile& pool, const SectionEntry* entry,
                              std::span<const std::uint32_t> nodes, std::uint32_t leaf_count,
                              std::uint32_t max_level, bool leaves_at_max_level, const std::string& where,
                              NodeType leaf_type) {
    const std::string leaf_word = leaf_type == NodeType::brick ? "brick " : "leaf ";
    // In index order from node 0: children must come after their parent, so a node's level is known
    // (and it is marked reachable) by the time it is checked; a second parent marks a node twice.
    const std::size_t count = nodes.size();
    std::vector<std::uint8_t> level(count, 0), seen(count, 0);
    std::vector<std::uint8_t> leaf_seen(leaf_count, 0);
    const auto fail_at = [&](std::size_t i, const std::string& what) {
        pool.fail(entry, where + "node " + std::to_string(i) + ": " + what);
    };
    seen[0] = 1;
    std::uint32_t deepest = 0;
    std::size_t reached = 1;
    for (std::size_t i = 0; i < count; ++i) {
        if (!seen[i]) continue;  // unreachable nodes are reported below
        const std::uint32_t a = node_address(nodes[i]);
        const NodeType type = node_type(nodes[i]);
        if (type == NodeType::internal) {
            if (level[i] >= max_level)
                fail_at(i, "an internal node at level " + std::to_string(level[i]) + " (max level " +
                               std::to_string(max_level) + ")");
            if (a <= i || std::uint64_t(a) + 8 > count)
                fail_at(i, "children at " + std::to_string(a) + " not after it or out of range");
            for (std::uint32_t c = 0; c < 8; ++c) {
                if (seen[a + c]) fail_at(i, "child " + std::to_string(a + c) + " has two parents");
                seen[a + c] = 1;
                level[a + c] = static_cast<std::uint8_t>(level[i] + 1);
            }
            reached += 8;
        } else if (type == leaf_type) {
            if (leaves_at_max_level && level[i] != max_level)
                fail_at(i, "filled leaf at level " + std::to_string(level[i]) + ", not " +
                               std::to_string(max_level));
            if (a >= leaf_count)
                fail_at(i, leaf_word + std::to_string(a) + " out of range (" + std::to_string(leaf_count) +
                               " " + (leaf_type == NodeType::brick ? "bricks)" : "leaves)"));
            if (leaf_seen[a]++) fail_at(i, leaf_word + std::to_string(a) + " addressed twice");
            deepest = std::max<std::uint32_t>(deepest, level[i]);
        } else if (type != NodeType::empty_leaf) {
            fail_at(i, "invalid node type " + std::to_string(static_cast<std::uint32_t>(type)));
        }
    }
    if (reached != count)
        pool.fail(entry, where + std::to_string(count - reached) + " nodes not reachable from the root");
    for (std::uint32_t l = 0; l < leaf_count; ++l)
        if (!leaf_seen[l]) pool.fail(entry, where + leaf_word + std::to_string(l) + " is in no node");
    return deepest;
}

}  // namespace prt::pool::detail
