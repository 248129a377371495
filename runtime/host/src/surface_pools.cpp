// PointRT runtime (host): the ISO, MLS and patch sections of a pool validated into the core's
// views (formats/POOL.md "Implicit Surface Octree", "MLS surface", "Bezier patches"). Every
// cross-reference a traversal relies on is checked here, so a bad pool gives a one-line error
// "FILE: section NAME: what is wrong" instead of a crash, an endless loop or a garbage image. The
// preprocessing tools that write these sections (preprocess/iso, mls, patches) read them back
// through the same functions.
#include "prt/runtime/surface_pools.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <string>
#include <vector>

namespace prt::rt {

using pool::SectionType;

// ---- Implicit Surface Octree (thesis 4.4) ----------------------------------------------------------

bool has_iso(const pool::PoolFile& pool) {
    return pool.has(SectionType::iso_info) || pool.has(SectionType::iso_nodes) ||
           pool.has(SectionType::iso_leaves_q8) || pool.has(SectionType::iso_leaves_f32);
}


core::IsoView make_iso_view(const pool::IsoInfo& info, const std::uint32_t* nodes, const pool::IsoLeafQ8* q8,
                      const pool::IsoLeafF32* f32, bool prefer_q8) {
    core::IsoView v;
    v.tree.nodes = nodes;
    v.tree.node_count = info.node_count;
    v.tree.filled_leaves = info.leaf_count;
    v.tree.root_min = core::Vec3{info.root_min[0], info.root_min[1], info.root_min[2]};
    v.tree.root_size = info.root_size;
    v.tree.inv_root_size = 1.0f / info.root_size;
    v.leaves_q8 = q8;
    v.leaves_f32 = f32;
    v.leaf_count = info.leaf_count;
    v.flags = info.flags;
    v.use_q8 = (prefer_q8 && q8 != nullptr) || f32 == nullptr ? 1u : 0u;
    return v;
}

core::IsoView load_iso_view(const pool::PoolFile& pool, bool prefer_q8) {
    const pool::SectionEntry* ei = pool.find(SectionType::iso_info);
    const pool::SectionEntry* en = pool.find(SectionType::iso_nodes);
    const pool::SectionEntry* eq = pool.find(SectionType::iso_leaves_q8);
    const pool::SectionEntry* ef = pool.find(SectionType::iso_leaves_f32);
    if (!ei || !en) {
        const pool::SectionEntry* any = ei ? ei : en ? en : eq ? eq : ef;
        pool.fail(any, any ? "the ISO needs iso_info and iso_nodes" : "no ISO sections (run prt-iso)");
    }
    const auto infos = pool.array<pool::IsoInfo>(SectionType::iso_info);
    const auto nodes = pool.array<std::uint32_t>(SectionType::iso_nodes);
    const auto q8 = pool.array<pool::IsoLeafQ8>(SectionType::iso_leaves_q8);
    const auto f32 = pool.array<pool::IsoLeafF32>(SectionType::iso_leaves_f32);
    if (infos.size() != 1) pool.fail(ei, "must hold exactly one element");
    const pool::IsoInfo& info = infos[0];
    for (int a = 0; a < 3; ++a)
        if (!std::isfinite(info.root_min[a])) pool.fail(ei, "root corner not finite");
    if (!(info.root_size > 0.0f) || !std::isfinite(info.root_size) || !std::isfinite(1.0f / info.root_size))
        pool.fail(ei, "root edge not finite and positive");
    if (info.max_level > pool::k_max_iso_level || info.min_level > info.max_level ||
        info.depth > info.max_level)
        pool.fail(ei, "levels min " + std::to_string(info.min_level) + ", max " +
                          std::to_string(info.max_level) + ", depth " + std::to_string(info.depth) +
                          " are inconsistent or exceed " + std::to_string(pool::k_max_iso_level));
    if (nodes.size() != info.node_count || nodes.empty())
        pool.fail(
            en, std::to_string(nodes.size()) + " nodes but iso_info says " + std::to_string(info.node_count));
    const bool want_q8 = (info.flags & pool::k_iso_has_q8) != 0,
               want_f32 = (info.flags & pool::k_iso_has_f32) != 0;
    if (!want_q8 && !want_f32) pool.fail(ei, "flags name no leaf array");
    if (want_q8 != (eq != nullptr))
        pool.fail(eq ? eq : ei, want_q8 ? "section iso_leaves_q8 missing (iso_info's flags name it)"
                                        : "present but iso_info's flags do not name it");
    if (want_f32 != (ef != nullptr))
        pool.fail(ef ? ef : ei, want_f32 ? "section iso_leaves_f32 missing (iso_info's flags name it)"
                                         : "present but iso_info's flags do not name it");
    if (eq && q8.size() != info.leaf_count)
        pool.fail(eq,
                  std::to_string(q8.size()) + " leaves but iso_info says " + std::to_string(info.leaf_count));
    if (ef && f32.size() != info.leaf_count)
        pool.fail(
            ef, std::to_string(f32.size()) + " leaves but iso_info says " + std::to_string(info.leaf_count));

    // The tree: breadth first from node 0, each child group after its parent and reached once,
    // filled leaves addressing every leaf exactly once.
    const std::uint32_t count = info.node_count;
    std::vector<std::uint8_t> level(count, 0), seen(count, 0);
    std::vector<std::uint8_t> leaf_seen(info.leaf_count, 0);
    seen[0] = 1;
    std::uint32_t deepest = 0, reached = 1;
    for (std::uint32_t i = 0; i < count; ++i) {
        if (!seen[i]) continue;  // unreachable nodes are reported below
        const std::uint32_t w = nodes[i];
        const auto type = static_cast<std::uint32_t>(pool::node_type(w));
        const std::uint32_t a = pool::node_address(w);
        const std::string node = "node " + std::to_string(i) + ": ";
        if (type == static_cast<std::uint32_t>(pool::NodeType::internal)) {
            if (level[i] >= info.max_level)
                pool.fail(en, node + "an internal node at level " + std::to_string(level[i]) +
                                  " (max level " + std::to_string(info.max_level) + ")");
            if (a <= i || a > count || count - a < 8)
                pool.fail(en, node + "children at " + std::to_string(a) + " not after it or out of range");
            for (std::uint32_t c = 0; c < 8; ++c) {
                if (seen[a + c]) pool.fail(en, node + "child " + std::to_string(a + c) + " has two parents");
                seen[a + c] = 1;
                level[a + c] = static_cast<std::uint8_t>(level[i] + 1);
            }
            reached += 8;
        } else if (type == static_cast<std::uint32_t>(pool::NodeType::filled_leaf)) {
            if (a >= info.leaf_count)
                pool.fail(en, node + "leaf " + std::to_string(a) + " out of range (" +
                                  std::to_string(info.leaf_count) + " leaves)");
            if (leaf_seen[a]++) pool.fail(en, node + "leaf " + std::to_string(a) + " addressed twice");
            deepest = std::max<std::uint32_t>(deepest, level[i]);
        } else if (type != static_cast<std::uint32_t>(pool::NodeType::empty_leaf)) {
            pool.fail(en, node + "invalid node type 3");
        }
    }
    if (reached != count)
        pool.fail(en, std::to_string(count - reached) + " nodes not reachable from the root");
    for (std::uint32_t l = 0; l < info.leaf_count; ++l)
        if (!leaf_seen[l]) pool.fail(en, "leaf " + std::to_string(l) + " is in no node");
    if (info.leaf_count > 0 && deepest != info.depth)
        pool.fail(en, "deepest filled leaf at level " + std::to_string(deepest) + " but iso_info says " +
                          std::to_string(info.depth));
    for (std::size_t l = 0; l < f32.size(); ++l) {
        for (int c = 0; c < 8; ++c) {
            bool ok = std::isfinite(f32[l].value[c]);
            for (int a = 0; a < 3; ++a) ok = ok && std::isfinite(f32[l].normal[c][a]);
            if (!ok) pool.fail(ef, "leaf " + std::to_string(l) + ": value or normal not finite");
        }
    }
    return make_iso_view(info, nodes.data(), eq ? q8.data() : nullptr, ef ? f32.data() : nullptr, prefer_q8);
}

// ---- MLS kd-tree (WS05 3.4) -------------------------------------------------------------------------

bool has_mls(const pool::PoolFile& pool) {
    return pool.has(SectionType::mls_info) || pool.has(SectionType::mls_nodes) ||
           pool.has(SectionType::mls_refs) || pool.has(SectionType::mls_splats);
}

core::MlsView make_mls_view(const pool::MlsInfo& info, const pool::MlsNode* nodes, const std::uint32_t* refs,
                            const pool::MlsSplat* splats) {
    core::MlsView view;
    view.nodes = nodes;
    view.refs = refs;
    view.splats = splats;
    view.node_count = info.node_count;
    view.ref_count = info.ref_count;
    view.splat_count = info.splat_count;
    view.depth = info.depth;
    view.root_lo = core::Vec3{info.root_lo[0], info.root_lo[1], info.root_lo[2]};
    view.root_hi = core::Vec3{info.root_hi[0], info.root_hi[1], info.root_hi[2]};
    return view;
}

core::MlsView load_mls_view(const pool::PoolFile& pool) {
    const pool::SectionEntry* ei = pool.find(SectionType::mls_info);
    const pool::SectionEntry* en = pool.find(SectionType::mls_nodes);
    const pool::SectionEntry* er = pool.find(SectionType::mls_refs);
    const pool::SectionEntry* es = pool.find(SectionType::mls_splats);
    if (!ei || !en || !er || !es) {
        const pool::SectionEntry* any = ei ? ei : en ? en : er ? er : es;
        pool.fail(any, any ? "the MLS surface needs all of mls_info, mls_nodes, mls_refs, mls_splats"
                           : "no MLS sections (run prt-mls)");
    }
    const auto infos = pool.array<pool::MlsInfo>(SectionType::mls_info);
    const auto nodes = pool.array<pool::MlsNode>(SectionType::mls_nodes);
    const auto refs = pool.array<std::uint32_t>(SectionType::mls_refs);
    const auto splats = pool.array<pool::MlsSplat>(SectionType::mls_splats);
    if (infos.size() != 1) pool.fail(ei, "must hold exactly one element");
    const pool::MlsInfo& info = infos[0];
    if (info.node_count != nodes.size())
        pool.fail(
            en, std::to_string(nodes.size()) + " nodes but mls_info says " + std::to_string(info.node_count));
    if (info.ref_count != refs.size())
        pool.fail(er,
                  std::to_string(refs.size()) + " refs but mls_info says " + std::to_string(info.ref_count));
    if (info.splat_count != splats.size())
        pool.fail(es, std::to_string(splats.size()) + " splats but mls_info says " +
                          std::to_string(info.splat_count));
    if (nodes.empty()) pool.fail(en, "no nodes (the root is missing)");
    if (nodes.size() - 1 > pool::k_mls_index_max) pool.fail(en, "more nodes than 30-bit indices address");
    if (info.depth > pool::k_max_mls_depth)
        pool.fail(
            ei, "depth " + std::to_string(info.depth) + " exceeds " + std::to_string(pool::k_max_mls_depth));
    for (int a = 0; a < 3; ++a)
        if (!std::isfinite(info.root_lo[a]) || !std::isfinite(info.root_hi[a]) ||
            info.root_lo[a] > info.root_hi[a])
            pool.fail(ei, "root cell not finite or inverted");
    if (!std::isfinite(info.support_factor) || !(info.support_factor > 0.0f))
        pool.fail(ei, "support factor not finite and > 0");
    if (info.samples < 2) pool.fail(ei, "samples per cell must be at least 2");

    const std::uint64_t points = pool.model_info().point_count;
    for (std::size_t i = 0; i < splats.size(); ++i) {
        const pool::MlsSplat& s = splats[i];
        const float v[7] = {s.position.x, s.position.y, s.position.z, s.normal.x,
                            s.normal.y,   s.normal.z,   s.inv_support};
        for (const float x : v)
            if (!std::isfinite(x)) pool.fail(es, "splat " + std::to_string(i) + ": a value is not finite");
        if (!(s.inv_support > 0.0f)) pool.fail(es, "splat " + std::to_string(i) + ": support radius not > 0");
        if (s.point >= points)
            pool.fail(es, "splat " + std::to_string(i) + ": point " + std::to_string(s.point) +
                              " out of range (model_info has " + std::to_string(points) + " points)");
    }
    for (std::size_t k = 0; k < refs.size(); ++k)
        if (refs[k] >= splats.size())
            pool.fail(er,
                      "ref " + std::to_string(k) + ": splat " + std::to_string(refs[k]) + " out of range");

    // The tree: walked from the root with its cells; each node reached exactly once (children are
    // after their parent, so no cycles), split planes inside their cell, leaves covering mls_refs.
    struct Item {
        std::uint32_t node, depth;
        float lo[3], hi[3];
    };
    std::vector<char> seen(nodes.size(), 0);
    std::vector<char> covered(refs.size(), 0);
    Item root{0, 0, {}, {}};
    for (int a = 0; a < 3; ++a) {
        root.lo[a] = info.root_lo[a];
        root.hi[a] = info.root_hi[a];
    }
    std::vector<Item> stack{root};
    std::uint32_t deepest = 0, leaves = 0;
    std::uint64_t visited = 0;
    while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        const std::string at = "node " + std::to_string(it.node) + ": ";
        if (seen[it.node]++) pool.fail(en, at + "reached twice (not a tree)");
        ++visited;
        if (it.depth > pool::k_max_mls_depth)
            pool.fail(en, at + "deeper than " + std::to_string(pool::k_max_mls_depth));
        deepest = std::max(deepest, it.depth);
        const pool::MlsNode& n = nodes[it.node];
        if (pool::mls_node_is_leaf(n)) {
            ++leaves;
            const std::uint64_t first = pool::mls_leaf_first(n), count = pool::mls_leaf_count(n);
            if (first + count > refs.size())
                pool.fail(en, at + "refs " + std::to_string(first) + "+" + std::to_string(count) +
                                  " beyond the " + std::to_string(refs.size()) + " refs");
            for (std::uint64_t k = first; k < first + count; ++k)
                if (covered[k]++) pool.fail(en, at + "ref " + std::to_string(k) + " belongs to two leaves");
            continue;
        }
        const std::uint32_t axis = pool::mls_node_axis(n);
        const std::uint32_t left = pool::mls_node_left(n);
        const float split = core::mls_node_split(n);
        if (left <= it.node || std::uint64_t(left) + 1 >= nodes.size())
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
    if (visited != nodes.size())
        pool.fail(en, std::to_string(nodes.size() - visited) + " nodes not reachable from the root");
    for (std::size_t k = 0; k < covered.size(); ++k)
        if (!covered[k]) pool.fail(er, "ref " + std::to_string(k) + " belongs to no leaf");
    if (deepest != info.depth)
        pool.fail(en,
                  "depth " + std::to_string(deepest) + " but mls_info says " + std::to_string(info.depth));
    if (leaves != info.leaf_count)
        pool.fail(en,
                  std::to_string(leaves) + " leaves but mls_info says " + std::to_string(info.leaf_count));

    return make_mls_view(info, nodes.data(), refs.data(), splats.data());
}

// ---- Bezier patches (seed 002, 5.1) --------------------------------------------------------------

namespace {

bool finite_box(const float lo[3], const float hi[3]) {
    for (int a = 0; a < 3; ++a)
        if (!std::isfinite(lo[a]) || !std::isfinite(hi[a]) || lo[a] > hi[a]) return false;
    return true;
}

}  // namespace

bool has_patches(const pool::PoolFile& pool) {
    return pool.has(SectionType::patch_info) || pool.has(SectionType::patch_control_points) ||
           pool.has(SectionType::patch_bvh) || pool.has(SectionType::patch_subpatch_boxes);
}

core::PatchView load_patch_view(const pool::PoolFile& pool) {
    const pool::SectionEntry* ei = pool.find(SectionType::patch_info);
    const pool::SectionEntry* ec = pool.find(SectionType::patch_control_points);
    const pool::SectionEntry* eb = pool.find(SectionType::patch_bvh);
    const pool::SectionEntry* es = pool.find(SectionType::patch_subpatch_boxes);
    if (!ei || !ec || !eb || !es) {
        const pool::SectionEntry* any = ei ? ei : ec ? ec : eb ? eb : es;
        pool.fail(any, any ? "the patches need all of patch_info, patch_control_points, patch_bvh, "
                             "patch_subpatch_boxes"
                           : "no patch sections (run prt-patches)");
    }
    const auto infos = pool.array<pool::PatchInfo>(SectionType::patch_info);
    const auto nets = pool.array<pool::PatchControlNet>(SectionType::patch_control_points);
    const auto bvh = pool.array<pool::PatchBvhNode>(SectionType::patch_bvh);
    const auto nodes = pool.array<pool::SubpatchNode>(SectionType::patch_subpatch_boxes);
    if (infos.size() != 1) pool.fail(ei, "must hold exactly one element");
    const pool::PatchInfo& info = infos[0];
    if (info.patch_count == 0 || info.patch_count > pool::k_max_patches)
        pool.fail(ei, "patch count " + std::to_string(info.patch_count) + " outside 1.." +
                          std::to_string(pool::k_max_patches));
    if (info.subpatch_depth > pool::k_max_subpatch_depth)
        pool.fail(ei, "subpatch depth " + std::to_string(info.subpatch_depth) + " exceeds " +
                          std::to_string(pool::k_max_subpatch_depth));
    if (info.subpatch_nodes != (2u << info.subpatch_depth) - 1u)
        pool.fail(ei, std::to_string(info.subpatch_nodes) + " subpatch nodes per patch, depth " +
                          std::to_string(info.subpatch_depth) + " needs " +
                          std::to_string((2u << info.subpatch_depth) - 1u));
    if (info.bvh_node_count != 2 * info.patch_count - 1)
        pool.fail(ei, std::to_string(info.bvh_node_count) + " BVH nodes for " +
                          std::to_string(info.patch_count) + " patches (one patch per leaf needs " +
                          std::to_string(2 * info.patch_count - 1) + ")");
    if (info.bvh_depth > pool::k_max_patch_bvh_depth)
        pool.fail(ei, "BVH depth " + std::to_string(info.bvh_depth) + " exceeds " +
                          std::to_string(pool::k_max_patch_bvh_depth));
    if (!finite_box(info.bounds_min, info.bounds_max)) pool.fail(ei, "bounds not finite or inverted");
    if (nets.size() != info.patch_count)
        pool.fail(ec, std::to_string(nets.size()) + " control nets but patch_info says " +
                          std::to_string(info.patch_count) + " patches");
    if (bvh.size() != info.bvh_node_count)
        pool.fail(eb, std::to_string(bvh.size()) + " nodes but patch_info says " +
                          std::to_string(info.bvh_node_count));
    const std::uint64_t want_nodes = std::uint64_t(info.patch_count) * info.subpatch_nodes;
    if (nodes.size() != want_nodes)
        pool.fail(es, std::to_string(nodes.size()) + " boxes but patch_info says " +
                          std::to_string(info.patch_count) + " x " + std::to_string(info.subpatch_nodes));

    for (std::size_t p = 0; p < nets.size(); ++p)
        for (const pool::PatchPoint& q : nets[p].p)
            if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z))
                pool.fail(ec, "patch " + std::to_string(p) + ": control point not finite");
    for (std::size_t k = 0; k < nodes.size(); ++k)
        if (!finite_box(nodes[k].lo, nodes[k].hi) || !(nodes[k].cone_cos <= 1.0f))
            pool.fail(es, "box " + std::to_string(k) + ": not finite, inverted, or a cone cosine above 1");

    // The BVH: node 0 spans [0, n); an interior node i spanning [i, end) has its left child at
    // i + 1 spanning [i + 1, r) and its right child at r = bvh[i + 1].skip spanning [r, end); a
    // leaf spans [i, i + 1). Each node's skip must be its span's end; every patch in one leaf.
    const std::uint32_t n = info.bvh_node_count;
    std::vector<char> seen(info.patch_count, 0);
    struct Span {
        std::uint32_t node, end, depth;
    };
    std::vector<Span> stack{{0, n, 0}};
    std::uint32_t deepest = 0, visited = 0;
    while (!stack.empty()) {
        const Span s = stack.back();
        stack.pop_back();
        ++visited;
        const pool::PatchBvhNode& node = bvh[s.node];
        const std::string at = "node " + std::to_string(s.node) + ": ";
        if (s.depth > pool::k_max_patch_bvh_depth)
            pool.fail(eb, at + "deeper than " + std::to_string(pool::k_max_patch_bvh_depth));
        deepest = std::max(deepest, s.depth);
        if (!finite_box(node.lo, node.hi)) pool.fail(eb, at + "box not finite or inverted");
        if (node.skip != s.end)
            pool.fail(eb, at + "skip " + std::to_string(node.skip) + ", expected " + std::to_string(s.end));
        if (node.patch >= 0) {
            if (s.end != s.node + 1) pool.fail(eb, at + "a leaf whose subtree is not one node");
            if (static_cast<std::uint32_t>(node.patch) >= info.patch_count)
                pool.fail(eb, at + "patch " + std::to_string(node.patch) + " out of range");
            if (seen[node.patch]++)
                pool.fail(eb, at + "patch " + std::to_string(node.patch) + " in two leaves");
        } else {
            if (node.patch != -1)
                pool.fail(eb, at + "patch index " + std::to_string(node.patch) + " is invalid");
            if (s.node + 2 >= s.end) pool.fail(eb, at + "an interior node without two children");
            const std::uint32_t right = bvh[s.node + 1].skip;
            if (right <= s.node + 1 || right >= s.end)
                pool.fail(eb, at + "right child " + std::to_string(right) + " outside its subtree");
            stack.push_back({right, s.end, s.depth + 1});
            stack.push_back({s.node + 1, right, s.depth + 1});
        }
    }
    if (visited != n) pool.fail(eb, std::to_string(n - visited) + " nodes not reachable from the root");
    if (deepest != info.bvh_depth)
        pool.fail(eb, "depth " + std::to_string(deepest) + " but patch_info says " +
                          std::to_string(info.bvh_depth));
    for (std::uint32_t p = 0; p < info.patch_count; ++p)
        if (!seen[p]) pool.fail(eb, "patch " + std::to_string(p) + " is in no leaf");

    core::PatchView view;
    view.nets = nets.data();
    view.bvh = bvh.data();
    view.nodes = nodes.data();
    view.patch_count = info.patch_count;
    view.bvh_node_count = info.bvh_node_count;
    view.subpatch_depth = info.subpatch_depth;
    view.subpatch_nodes = info.subpatch_nodes;
    view.flags = info.flags;
    double extent = 0.0;
    for (int a = 0; a < 3; ++a)
        extent = std::max(extent, double(info.bounds_max[a]) - double(info.bounds_min[a]));
    view.extent = extent > 0.0 ? extent : 1.0;
    return view;
}

}  // namespace prt::rt
