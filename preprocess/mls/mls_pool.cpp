// PointRT: writing and validating the MLS sections (formats/POOL.md, "MLS surface").
#include "mls_pool.h"

#include <bit>
#include <cmath>
#include <string>
#include <vector>

namespace prt::mls {

using pool::SectionType;

bool has_mls(const pool::PoolFile& pool) {
    return pool.has(SectionType::mls_info) || pool.has(SectionType::mls_nodes) ||
           pool.has(SectionType::mls_refs) || pool.has(SectionType::mls_splats);
}

void write_mls_sections(MlsModel&& model, pool::PoolWriter& writer) {
    writer.add_array(SectionType::mls_info, std::vector<pool::MlsInfo>{model.info});
    writer.add_array(SectionType::mls_nodes, std::move(model.nodes));
    writer.add_array(SectionType::mls_refs, std::move(model.refs));
    writer.add_array(SectionType::mls_splats, std::move(model.splats));
}

core::MlsView make_view(const MlsModel& model) {
    core::MlsView view;
    view.nodes = model.nodes.data();
    view.refs = model.refs.data();
    view.splats = model.splats.data();
    view.node_count = static_cast<std::uint32_t>(model.nodes.size());
    view.ref_count = static_cast<std::uint32_t>(model.refs.size());
    view.splat_count = static_cast<std::uint32_t>(model.splats.size());
    view.depth = model.info.depth;
    view.root_lo = core::Vec3{model.info.root_lo[0], model.info.root_lo[1], model.info.root_lo[2]};
    view.root_hi = core::Vec3{model.info.root_hi[0], model.info.root_hi[1], model.info.root_hi[2]};
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

    core::MlsView view;
    view.nodes = nodes.data();
    view.refs = refs.data();
    view.splats = splats.data();
    view.node_count = info.node_count;
    view.ref_count = info.ref_count;
    view.splat_count = info.splat_count;
    view.depth = info.depth;
    view.root_lo = core::Vec3{info.root_lo[0], info.root_lo[1], info.root_lo[2]};
    view.root_hi = core::Vec3{info.root_hi[0], info.root_hi[1], info.root_hi[2]};
    return view;
}

}  // namespace prt::mls
