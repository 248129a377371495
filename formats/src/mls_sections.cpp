// PointRT pool file: validation of the exact MLS surface sections (mls_sections.h; rules in
// formats/POOL.md, "MLS surface"): a bad pool is a one-line error, never a crash or an endless loop.
#include "prt/formats/mls_sections.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <string>
#include <vector>

#include "section_checks.h"

namespace prt::pool {

namespace {

constexpr SectionType k_mls_types[] = {SectionType::mls_info, SectionType::mls_nodes, SectionType::mls_refs,
                                       SectionType::mls_splats};

/// Counts as mls_info says, the root present and addressable, depth, root cell and build parameters.
void check_mls_info(const PoolFile& pool, const MlsSections& s) {
    const SectionEntry* ei = pool.find(SectionType::mls_info);
    const SectionEntry* en = pool.find(SectionType::mls_nodes);
    const MlsInfo& info = s.info;
    detail::check_count(pool, en, s.nodes.size(), info.node_count, "nodes", "mls_info");
    detail::check_count(pool, pool.find(SectionType::mls_refs), s.refs.size(), info.ref_count, "refs",
                        "mls_info");
    detail::check_count(pool, pool.find(SectionType::mls_splats), s.splats.size(), info.splat_count, "splats",
                        "mls_info");
    if (s.nodes.empty()) pool.fail(en, "no nodes (the root is missing)");
    if (s.nodes.size() - 1 > k_mls_index_max) pool.fail(en, "more nodes than 30-bit indices address");
    if (info.depth > k_max_mls_depth)
        pool.fail(ei, "depth " + std::to_string(info.depth) + " exceeds " + std::to_string(k_max_mls_depth));
    if (!detail::finite_box(info.root_lo, info.root_hi)) pool.fail(ei, "root cell not finite or inverted");
    if (!std::isfinite(info.support_factor) || !(info.support_factor > 0.0f))
        pool.fail(ei, "support factor not finite and > 0");
    if (info.samples < 2) pool.fail(ei, "samples per cell must be at least 2");
}

/// Splats finite with a positive support and a point in range; refs naming a splat.
void check_mls_splats(const PoolFile& pool, const MlsSections& s) {
    const SectionEntry* es = pool.find(SectionType::mls_splats);
    const std::uint64_t points = pool.model_info().point_count;
    for (std::size_t i = 0; i < s.splats.size(); ++i) {
        const MlsSplat& p = s.splats[i];
        const float v[7] = {p.position.x, p.position.y, p.position.z, p.normal.x,
                            p.normal.y,   p.normal.z,   p.inv_support};
        for (const float x : v)
            if (!std::isfinite(x)) pool.fail(es, "splat " + std::to_string(i) + ": a value is not finite");
        if (!(p.inv_support > 0.0f)) pool.fail(es, "splat " + std::to_string(i) + ": support radius not > 0");
        if (p.point >= points)
            pool.fail(es, "splat " + std::to_string(i) + ": point " + std::to_string(p.point) +
                              " out of range (model_info has " + std::to_string(points) + " points)");
    }
    const SectionEntry* er = pool.find(SectionType::mls_refs);
    for (std::size_t k = 0; k < s.refs.size(); ++k)
        if (s.refs[k] >= s.splats.size())
            pool.fail(er,
                      "ref " + std::to_string(k) + ": splat " + std::to_string(s.refs[k]) + " out of range");
}

/// The tree, walked from the root with its cells: each node reached exactly once (children are after
/// their parent, so no cycles), split planes inside their cell, leaves covering mls_refs exactly once.
void check_mls_tree(const PoolFile& pool, const MlsSections& s) {
    const SectionEntry* en = pool.find(SectionType::mls_nodes);
    struct Item {
        std::uint32_t node, depth;
        float lo[3], hi[3];
    };
    std::vector<char> seen(s.nodes.size(), 0);
    std::vector<char> covered(s.refs.size(), 0);
    Item root{0, 0, {}, {}};
    std::copy(s.info.root_lo, s.info.root_lo + 3, root.lo);
    std::copy(s.info.root_hi, s.info.root_hi + 3, root.hi);
    std::vector<Item> stack{root};
    std::uint32_t deepest = 0, leaves = 0;
    std::uint64_t visited = 0;
    while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        const std::string at = "node " + std::to_string(it.node) + ": ";
        if (seen[it.node]++) pool.fail(en, at + "reached twice (not a tree)");
        ++visited;
        if (it.depth > k_max_mls_depth) pool.fail(en, at + "deeper than " + std::to_string(k_max_mls_depth));
        deepest = std::max(deepest, it.depth);
        const MlsNode& n = s.nodes[it.node];
        if (mls_node_is_leaf(n)) {
            ++leaves;
            const std::uint64_t first = mls_leaf_first(n), count = mls_leaf_count(n);
            if (first + count > s.refs.size())
                pool.fail(en, at + "refs " + std::to_string(first) + "+" + std::to_string(count) +
                                  " beyond the " + std::to_string(s.refs.size()) + " refs");
            for (std::uint64_t k = first; k < first + count; ++k)
                if (covered[k]++) pool.fail(en, at + "ref " + std::to_string(k) + " belongs to two leaves");
            continue;
        }
        const std::uint32_t axis = mls_node_axis(n);
        const std::uint32_t left = mls_node_left(n);
        const float split = std::bit_cast<float>(n.payload);
        if (left <= it.node || std::uint64_t(left) + 1 >= s.nodes.size())
            pool.fail(en, at + "children " + std::to_string(left) + ", " + std::to_string(left + 1) +
                              " not after it or out of range");
        if (!std::isfinite(split) || split < it.lo[axis] || split > it.hi[axis])
            pool.fail(en, at + "split plane outside its cell");
        Item l = it, r = it;
        l.node = left;
        r.node = left + 1;
        l.depth = r.depth = it.depth + 1;
        l.hi[axis] = split;
        r.lo[axis] = split;
        stack.push_back(r);
        stack.push_back(l);
    }
    if (visited != s.nodes.size())
        pool.fail(en, std::to_string(s.nodes.size() - visited) + " nodes not reachable from the root");
    for (std::size_t k = 0; k < covered.size(); ++k)
        if (!covered[k])
            pool.fail(pool.find(SectionType::mls_refs), "ref " + std::to_string(k) + " belongs to no leaf");
    if (deepest != s.info.depth)
        pool.fail(en,
                  "depth " + std::to_string(deepest) + " but mls_info says " + std::to_string(s.info.depth));
    detail::check_count(pool, en, leaves, s.info.leaf_count, "leaves", "mls_info");
}

}  // namespace

bool has_mls(const PoolFile& pool) {
    return detail::first_present(pool, k_mls_types) != nullptr;
}

MlsSections validate_mls(const PoolFile& pool) {
    detail::require_sections(pool, k_mls_types, 4,
                             "the MLS surface needs all of mls_info, mls_nodes, mls_refs, mls_splats", "MLS");
    MlsSections s;
    s.nodes = pool.array<MlsNode>(SectionType::mls_nodes);
    s.refs = pool.array<std::uint32_t>(SectionType::mls_refs);
    s.splats = pool.array<MlsSplat>(SectionType::mls_splats);
    s.info = detail::single<MlsInfo>(pool, SectionType::mls_info);
    check_mls_info(pool, s);
    check_mls_splats(pool, s);
    check_mls_tree(pool, s);
    return s;
}

}  // namespace prt::pool
