// PointRT pool file: validation of the Bezier patch sections (patch_sections.h; rules in
// formats/POOL.md, "Bezier patches", seed 002 5.1).
#include "prt/formats/patch_sections.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "section_checks.h"

namespace prt::pool {

namespace {

constexpr SectionType k_patch_types[] = {SectionType::patch_info, SectionType::patch_control_points,
                                         SectionType::patch_bvh, SectionType::patch_subpatch_boxes};

/// The counts and limits of patch_info, and the section sizes they imply.
void check_patch_info(const PoolFile& pool, const PatchSections& s) {
    const SectionEntry* ei = pool.find(SectionType::patch_info);
    const PatchInfo& info = s.info;
    if (info.patch_count == 0 || info.patch_count > k_max_patches)
        pool.fail(ei, "patch count " + std::to_string(info.patch_count) + " outside 1.." +
                          std::to_string(k_max_patches));
    if (info.subpatch_depth > k_max_subpatch_depth)
        pool.fail(ei, "subpatch depth " + std::to_string(info.subpatch_depth) + " exceeds " +
                          std::to_string(k_max_subpatch_depth));
    if (info.subpatch_nodes != (2u << info.subpatch_depth) - 1u)
        pool.fail(ei, std::to_string(info.subpatch_nodes) + " subpatch nodes per patch, depth " +
                          std::to_string(info.subpatch_depth) + " needs " +
                          std::to_string((2u << info.subpatch_depth) - 1u));
    if (info.bvh_node_count != 2 * info.patch_count - 1)
        pool.fail(ei, std::to_string(info.bvh_node_count) + " BVH nodes for " +
                          std::to_string(info.patch_count) + " patches (one patch per leaf needs " +
                          std::to_string(2 * info.patch_count - 1) + ")");
    if (info.bvh_depth > k_max_patch_bvh_depth)
        pool.fail(ei, "BVH depth " + std::to_string(info.bvh_depth) + " exceeds " +
                          std::to_string(k_max_patch_bvh_depth));
    if (!detail::finite_box(info.bounds_min, info.bounds_max)) pool.fail(ei, "bounds not finite or inverted");
    if (s.nets.size() != info.patch_count)
        pool.fail(pool.find(SectionType::patch_control_points),
                  std::to_string(s.nets.size()) + " control nets but patch_info says " +
                      std::to_string(info.patch_count) + " patches");
    detail::check_count(pool, pool.find(SectionType::patch_bvh), s.bvh.size(), info.bvh_node_count, "nodes",
                        "patch_info");
    const std::uint64_t want_boxes = std::uint64_t(info.patch_count) * info.subpatch_nodes;
    if (s.boxes.size() != want_boxes)
        pool.fail(pool.find(SectionType::patch_subpatch_boxes),
                  std::to_string(s.boxes.size()) + " boxes but patch_info says " +
                      std::to_string(info.patch_count) + " x " + std::to_string(info.subpatch_nodes));
}

/// Every control point finite; every subpatch box finite, not inverted, its cone cosine at most 1.
void check_patch_values(const PoolFile& pool, const PatchSections& s) {
    for (std::size_t p = 0; p < s.nets.size(); ++p)
        for (const PatchPoint& q : s.nets[p].p)
            if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z))
                pool.fail(pool.find(SectionType::patch_control_points),
                          "patch " + std::to_string(p) + ": control point not finite");
    for (std::size_t k = 0; k < s.boxes.size(); ++k)
        if (!detail::finite_box(s.boxes[k].lo, s.boxes[k].hi) || !(s.boxes[k].cone_cos <= 1.0f))
            pool.fail(pool.find(SectionType::patch_subpatch_boxes),
                      "box " + std::to_string(k) + ": not finite, inverted, or a cone cosine above 1");
}

/// The BVH: node 0 spans [0, n); an interior node i spanning [i, end) has its left child at i + 1
/// spanning [i + 1, r) and its right child at r = bvh[i + 1].skip spanning [r, end); a leaf spans
/// [i, i + 1). Each node's skip must be its span's end; every patch in one leaf.
void check_patch_bvh(const PoolFile& pool, const PatchSections& s) {
    const SectionEntry* eb = pool.find(SectionType::patch_bvh);
    const std::uint32_t n = s.info.bvh_node_count;
    std::vector<char> seen(s.info.patch_count, 0);
    struct Span {
        std::uint32_t node, end, depth;
    };
    std::vector<Span> stack{{0, n, 0}};
    std::uint32_t deepest = 0, visited = 0;
    while (!stack.empty()) {
        const Span sp = stack.back();
        stack.pop_back();
        ++visited;
        const PatchBvhNode& node = s.bvh[sp.node];
        const std::string at = "node " + std::to_string(sp.node) + ": ";
        if (sp.depth > k_max_patch_bvh_depth)
            pool.fail(eb, at + "deeper than " + std::to_string(k_max_patch_bvh_depth));
        deepest = std::max(deepest, sp.depth);
        if (!detail::finite_box(node.lo, node.hi)) pool.fail(eb, at + "box not finite or inverted");
        if (node.skip != sp.end)
            pool.fail(eb, at + "skip " + std::to_string(node.skip) + ", expected " + std::to_string(sp.end));
        if (node.patch >= 0) {
            if (sp.end != sp.node + 1) pool.fail(eb, at + "a leaf whose subtree is not one node");
            if (static_cast<std::uint32_t>(node.patch) >= s.info.patch_count)
                pool.fail(eb, at + "patch " + std::to_string(node.patch) + " out of range");
            if (seen[node.patch]++)
                pool.fail(eb, at + "patch " + std::to_string(node.patch) + " in two leaves");
        } else {
            if (node.patch != -1)
                pool.fail(eb, at + "patch index " + std::to_string(node.patch) + " is invalid");
            if (sp.node + 2 >= sp.end) pool.fail(eb, at + "an interior node without two children");
            const std::uint32_t right = s.bvh[sp.node + 1].skip;
            if (right <= sp.node + 1 || right >= sp.end)
                pool.fail(eb, at + "right child " + std::to_string(right) + " outside its subtree");
            stack.push_back({right, sp.end, sp.depth + 1});
            stack.push_back({sp.node + 1, right, sp.depth + 1});
        }
    }
    if (visited != n) pool.fail(eb, std::to_string(n - visited) + " nodes not reachable from the root");
    if (deepest != s.info.bvh_depth)
        pool.fail(eb, "depth " + std::to_string(deepest) + " but patch_info says " +
                          std::to_string(s.info.bvh_depth));
    for (std::uint32_t p = 0; p < s.info.patch_count; ++p)
        if (!seen[p]) pool.fail(eb, "patch " + std::to_string(p) + " is in no leaf");
}

}  // namespace

bool has_patches(const PoolFile& pool) {
    return detail::first_present(pool, k_patch_types) != nullptr;
}

PatchSections validate_patches(const PoolFile& pool) {
    detail::require_sections(pool, k_patch_types, 4,
                             "the patches need all of patch_info, patch_control_points, patch_bvh, "
                             "patch_subpatch_boxes",
                             "patch");
    PatchSections s;
    s.nets = pool.array<PatchControlNet>(SectionType::patch_control_points);
    s.bvh = pool.array<PatchBvhNode>(SectionType::patch_bvh);
    s.boxes = pool.array<SubpatchNode>(SectionType::patch_subpatch_boxes);
    s.info = detail::single<PatchInfo>(pool, SectionType::patch_info);
    check_patch_info(pool, s);
    check_patch_values(pool, s);
    check_patch_bvh(pool, s);
    return s;
}

}  // namespace prt::pool
