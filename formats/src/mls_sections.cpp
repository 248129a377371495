// PointRT pool file: validation of the exact MLS surface sections (mls_sections.h; rules in
// formats/POOL.md, "MLS surface"): a bad pool is a one-line error, never a crash or an endless loop.
#include "prt/formats/mls_sections.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "section_checks.h"

namespace prt::pool {

namespace {

constexpr SectionType k_mls_types[] = {SectionType::mls_info,      SectionType::mls_nodes,
                                       SectionType::mls_refs,      SectionType::mls_splats,
                                       SectionType::mls_bvh_nodes, SectionType::mls_bvh_leaves};

/// A non-empty kd leaf as the tree's walk bounds it: what a BVH leaf must repeat.
struct KdLeaf {
    std::uint32_t count;
    float lo[3], hi[3];
};

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
/// `leaves` receives, per first ref, each non-empty leaf's count and cell (for check_mls_bvh).
void check_mls_tree(const PoolFile& pool, const MlsSections& s, std::vector<KdLeaf>& leaves_by_first) {
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
    leaves_by_first.assign(s.refs.size(), KdLeaf{0, {}, {}});
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
            if (count > 0) {
                KdLeaf& kl = leaves_by_first[first];
                kl.count = static_cast<std::uint32_t>(count);
                std::copy(it.lo, it.lo + 3, kl.lo);
                std::copy(it.hi, it.hi + 3, kl.hi);
            }
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

/// The optional BVH over the non-empty kd leaves (both sections or neither): leaf_count - 1 nodes,
/// each node reached once from node 0 with its children after it, depth as recorded and at most
/// k_max_mls_bvh_depth, each leaf exactly one non-empty kd leaf (same refs, same cell) and every such
/// kd leaf one BVH leaf, and every child box holding what lies under it: a node's two boxes, a leaf's
/// cell cut to the box of its splats' support balls (so no ray skips a cell it would sample).
void check_mls_bvh(const PoolFile& pool, const MlsSections& s, const std::vector<KdLeaf>& kd) {
    const SectionEntry* en = pool.find(SectionType::mls_bvh_nodes);
    const SectionEntry* el = pool.find(SectionType::mls_bvh_leaves);
    const SectionEntry* ei = pool.find(SectionType::mls_info);
    if ((en == nullptr) != (el == nullptr))
        pool.fail(en ? en : el, "mls_bvh_nodes and mls_bvh_leaves go together (one is missing)");
    if (en == nullptr) {
        if (s.info.bvh_depth != 0) pool.fail(ei, "BVH depth recorded without the BVH sections");
        return;
    }
    std::uint64_t kd_leaves = 0;
    for (const KdLeaf& k : kd) kd_leaves += k.count > 0 ? 1 : 0;
    detail::check_count(pool, el, s.bvh_leaves.size(), kd_leaves, "BVH leaves",
                        "the kd-tree's non-empty leaves");
    if (s.bvh_leaves.size() < 2) pool.fail(el, "fewer than two leaves (the kd walk needs no BVH)");
    detail::check_count(pool, en, s.bvh_nodes.size(), s.bvh_leaves.size() - 1, "BVH nodes", "mls_bvh_leaves");
    if (s.bvh_leaves.size() > k_mls_bvh_leaf_bit) pool.fail(el, "more leaves than 31-bit indices address");
    if (s.info.bvh_depth > k_max_mls_bvh_depth)
        pool.fail(ei, "BVH depth " + std::to_string(s.info.bvh_depth) + " exceeds " +
                          std::to_string(k_max_mls_bvh_depth));
    // Leaves: each one kd leaf's refs and cell; the box its parent must hold.
    std::vector<double> content(s.bvh_leaves.size() * 6);
    for (std::size_t i = 0; i < s.bvh_leaves.size(); ++i) {
        const MlsBvhLeaf& l = s.bvh_leaves[i];
        const std::string at = "leaf " + std::to_string(i) + ": ";
        if (l.first >= kd.size() || kd[l.first].count == 0 || kd[l.first].count != l.count)
            pool.fail(el, at + "refs " + std::to_string(l.first) + "+" + std::to_string(l.count) +
                              " are no non-empty kd leaf's");
        const KdLeaf& k = kd[l.first];
        for (int a = 0; a < 3; ++a)
            if (std::bit_cast<std::uint32_t>(l.lo[a]) != std::bit_cast<std::uint32_t>(k.lo[a]) ||
                std::bit_cast<std::uint32_t>(l.hi[a]) != std::bit_cast<std::uint32_t>(k.hi[a]))
                pool.fail(el, at + "cell differs from its kd leaf's");
        double* c = &content[i * 6];
        for (int a = 0; a < 3; ++a) {
            c[a] = std::numeric_limits<double>::infinity();
            c[3 + a] = -std::numeric_limits<double>::infinity();
        }
        for (std::uint32_t r = l.first; r < l.first + l.count; ++r) {
            const MlsSplat& sp = s.splats[s.refs[r]];
            const double rad = 1.0 / double(sp.inv_support);
            const double p[3] = {sp.position.x, sp.position.y, sp.position.z};
            for (int a = 0; a < 3; ++a) {
                c[a] = std::min(c[a], p[a] - rad);
                c[3 + a] = std::max(c[3 + a], p[a] + rad);
            }
        }
        for (int a = 0; a < 3; ++a) {
            c[a] = std::max(c[a], double(l.lo[a]));
            c[3 + a] = std::min(c[3 + a], double(l.hi[a]));
        }
    }
    // Nodes from the root: children after their parent, each node and leaf reached once.
    std::vector<char> seen_node(s.bvh_nodes.size(), 0), seen_leaf(s.bvh_leaves.size(), 0);
    struct Item {
        std::uint32_t node, depth;
    };
    std::vector<Item> stack{{0, 0}};
    std::uint32_t deepest = 0;
    // Post-order check of the boxes: a node's content is the union of its children's boxes.
    while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        const std::string at = "node " + std::to_string(it.node) + ": ";
        if (seen_node[it.node]++) pool.fail(en, at + "reached twice (not a tree)");
        if (it.depth > k_max_mls_bvh_depth)
            pool.fail(en, at + "deeper than " + std::to_string(k_max_mls_bvh_depth));
        deepest = std::max(deepest, it.depth);
        for (const MlsBvhChild& c : s.bvh_nodes[it.node].child) {
            if (!detail::finite_box(c.lo, c.hi)) pool.fail(en, at + "a child box not finite or inverted");
            if (c.ref & k_mls_bvh_leaf_bit) {
                const std::uint32_t li = c.ref & ~k_mls_bvh_leaf_bit;
                if (li >= s.bvh_leaves.size())
                    pool.fail(en, at + "leaf " + std::to_string(li) + " out of range");
                if (seen_leaf[li]++) pool.fail(en, at + "leaf " + std::to_string(li) + " reached twice");
                const double* ct = &content[std::size_t{li} * 6];
                for (int a = 0; a < 3; ++a)
                    if (double(c.lo[a]) > ct[a] || double(c.hi[a]) < ct[3 + a])
                        pool.fail(en, at + "the box of leaf " + std::to_string(li) +
                                          " does not hold its cell's supports");
                continue;
            }
            if (c.ref <= it.node || c.ref >= s.bvh_nodes.size())
                pool.fail(en, at + "child " + std::to_string(c.ref) + " not after it or out of range");
            for (const MlsBvhChild& g : s.bvh_nodes[c.ref].child)
                for (int a = 0; a < 3; ++a)
                    if (!(c.lo[a] <= g.lo[a]) || !(c.hi[a] >= g.hi[a]))
                        pool.fail(en, at + "the box of node " + std::to_string(c.ref) +
                                          " does not hold its children");
            stack.push_back({c.ref, it.depth + 1});
        }
    }
    for (std::size_t i = 0; i < seen_node.size(); ++i)
        if (!seen_node[i]) pool.fail(en, "node " + std::to_string(i) + " not reachable from the root");
    for (std::size_t i = 0; i < seen_leaf.size(); ++i)
        if (!seen_leaf[i]) pool.fail(el, "leaf " + std::to_string(i) + " not reachable from the root");
    if (deepest != s.info.bvh_depth)
        pool.fail(en, "BVH depth " + std::to_string(deepest) + " but mls_info says " +
                          std::to_string(s.info.bvh_depth));
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
    if (pool.find(SectionType::mls_bvh_nodes))
        s.bvh_nodes = pool.array<MlsBvhNode>(SectionType::mls_bvh_nodes);
    if (pool.find(SectionType::mls_bvh_leaves))
        s.bvh_leaves = pool.array<MlsBvhLeaf>(SectionType::mls_bvh_leaves);
    std::vector<KdLeaf> kd_leaves;
    check_mls_tree(pool, s, kd_leaves);
    check_mls_bvh(pool, s, kd_leaves);
    return s;
}

}  // namespace prt::pool
