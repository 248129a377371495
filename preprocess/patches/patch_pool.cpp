// PointRT: validation of the patch sections (formats/POOL.md, "Bezier patches").
#include "patch_pool.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace prt::patches {

using pool::SectionType;

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

}  // namespace prt::patches
