// PointRT pool file: the splat octree sections, checked when a pool is opened (formats/POOL.md,
// "Validation" step 4) and read back as typed views (octree_sections.h).
#include "prt/formats/octree_sections.h"

#include <cmath>
#include <string>

#include "prt/parallel.h"
#include "section_checks.h"

namespace prt::pool {

namespace {
constexpr SectionType k_octree_types[] = {SectionType::octree_info, SectionType::octree_nodes,
                                          SectionType::leaf_info, SectionType::splats};
}  // namespace

namespace detail {

namespace {

/// Internal nodes point forward to eight children in range; filled leaves address leaf_info in range.
void check_octree_nodes(const PoolFile& pool, const SectionEntry* entry, std::span<const std::uint32_t> nodes,
                        std::uint32_t filled_leaves) {
    const auto bad = [&](std::size_t i) {
        const std::uint32_t a = node_address(nodes[i]);
        switch (node_type(nodes[i])) {
            case NodeType::internal:  // children come after their parent (breadth first), all 8 in range
                return a <= i || std::uint64_t(a) + 8 > nodes.size();
            case NodeType::filled_leaf:
                return a >= filled_leaves;
            case NodeType::empty_leaf:
                return false;
            default:
                return true;
        }
    };
    const std::size_t i =
        parallel_find_first(nodes.size(), resolve_threads(0), bad);  // the node a serial scan finds
    if (i == nodes.size()) return;
    const std::uint32_t a = node_address(nodes[i]);
    const std::string node = "node " + std::to_string(i) + ": ";
    if (node_type(nodes[i]) == NodeType::internal)
        pool.fail(entry, node + "child address " + std::to_string(a) + " out of range");
    if (node_type(nodes[i]) == NodeType::filled_leaf)
        pool.fail(entry, node + "leaf address " + std::to_string(a) + " out of range");
    pool.fail(entry, node + "invalid node type 3");
}

}  // namespace

void check_splat_octree(const PoolFile& pool, const ModelInfo& model) {
    const SectionEntry* oi = pool.find(SectionType::octree_info);
    const SectionEntry* on = pool.find(SectionType::octree_nodes);
    const SectionEntry* li = pool.find(SectionType::leaf_info);
    const SectionEntry* sp = pool.find(SectionType::splats);
    const int parts = (oi != nullptr) + (on != nullptr) + (li != nullptr) + (sp != nullptr);
    if (parts == 0) return;
    if (parts != 4)
        pool.fail(first_present(pool, k_octree_types),
                  "the octree needs all of octree_info, octree_nodes, leaf_info, splats");
    const OctreeInfo& o = single<OctreeInfo>(pool, SectionType::octree_info);
    check_count(pool, on, on->count, o.node_count, "nodes", "octree_info");
    if (std::uint64_t(o.filled_leaves) + 1 != li->count)
        pool.fail(li, std::to_string(li->count) + " entries but octree_info says " +
                          std::to_string(o.filled_leaves) + " filled leaves (+1)");
    check_count(pool, sp, sp->count, o.splat_count, "splats", "octree_info");
    if (!(o.root_size > 0) || !std::isfinite(o.root_size)) pool.fail(oi, "root size not positive and finite");
    if (o.node_count == 0) pool.fail(on, "empty node pool (no root)");
    check_octree_nodes(pool, on, pool.array<std::uint32_t>(SectionType::octree_nodes), o.filled_leaves);
    const auto leaves = pool.array<std::uint32_t>(SectionType::leaf_info);
    for (std::size_t i = 0; i + 1 < leaves.size(); ++i)
        if (leaves[i] > leaves[i + 1]) pool.fail(li, "leaf " + std::to_string(i) + ": begin after end");
    if (!leaves.empty() && (leaves.front() != 0 || leaves.back() != sp->count))
        pool.fail(li, "leaf ranges do not cover the splats exactly");
    const auto splats = pool.array<Splat>(SectionType::splats);
    if (model.point_count > 0) {
        const std::size_t i = parallel_find_first(splats.size(), resolve_threads(0), [&](std::size_t k) {
            return splats[k].point >= model.point_count;
        });
        if (i < splats.size())
            pool.fail(sp, "splat " + std::to_string(i) + ": point index " + std::to_string(splats[i].point) +
                              " out of range");
    }
}

}  // namespace detail

bool has_splat_octree(const PoolFile& pool) {
    return detail::first_present(pool, k_octree_types) != nullptr;
}

SplatOctreeSections splat_octree(const PoolFile& pool, const char* needed_by) {
    SplatOctreeSections s;
    s.info = pool.require<OctreeInfo>(SectionType::octree_info, needed_by)[0];
    s.nodes = pool.array<std::uint32_t>(SectionType::octree_nodes);
    s.leaf_info = pool.array<std::uint32_t>(SectionType::leaf_info);
    s.splats = pool.array<Splat>(SectionType::splats);
    return s;
}

}  // namespace prt::pool
