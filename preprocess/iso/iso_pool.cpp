// PointRT: writing and validating the ISO sections (formats/POOL.md, "Implicit Surface Octree").
#include "iso_pool.h"

#include <cmath>
#include <string>
#include <vector>

namespace prt::iso {

using pool::SectionType;

bool has_iso(const pool::PoolFile& pool) {
    return pool.has(SectionType::iso_info) || pool.has(SectionType::iso_nodes) ||
           pool.has(SectionType::iso_leaves_q8) || pool.has(SectionType::iso_leaves_f32);
}

void write_iso_sections(IsoModel&& model, pool::PoolWriter& writer) {
    writer.add_array(SectionType::iso_info, std::vector<pool::IsoInfo>{model.info});
    writer.add_array(SectionType::iso_nodes, std::move(model.nodes));
    if (model.info.flags & pool::k_iso_has_q8)
        writer.add_array(SectionType::iso_leaves_q8, std::move(model.leaves_q8));
    else
        writer.remove(SectionType::iso_leaves_q8);
    if (model.info.flags & pool::k_iso_has_f32)
        writer.add_array(SectionType::iso_leaves_f32, std::move(model.leaves_f32));
    else
        writer.remove(SectionType::iso_leaves_f32);
}

namespace {

core::IsoView view_of(const pool::IsoInfo& info, const std::uint32_t* nodes, const pool::IsoLeafQ8* q8,
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

}  // namespace

core::IsoView make_view(const IsoModel& model, bool prefer_q8) {
    return view_of(model.info, model.nodes.data(), model.leaves_q8.empty() ? nullptr : model.leaves_q8.data(),
                   model.leaves_f32.empty() ? nullptr : model.leaves_f32.data(), prefer_q8);
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
    return view_of(info, nodes.data(), eq ? q8.data() : nullptr, ef ? f32.data() : nullptr, prefer_q8);
}

}  // namespace prt::iso
