// PointRT pool file: validation of the Implicit Surface Octree sections (iso_sections.h; rules in
// formats/POOL.md, "Implicit Surface Octree"). Every cross-reference a traversal relies on is
// checked, so a bad pool is a one-line error instead of a crash, an endless loop or a garbage image.
#include "prt/formats/iso_sections.h"

#include <cmath>
#include <string>

#include "section_checks.h"

namespace prt::pool {

namespace {

constexpr SectionType k_iso_types[] = {SectionType::iso_info, SectionType::iso_nodes,
                                       SectionType::iso_leaves_q8, SectionType::iso_leaves_f32};

void check_iso_info(const PoolFile& pool, const SectionEntry* ei, const IsoInfo& info) {
    for (int a = 0; a < 3; ++a)
        if (!std::isfinite(info.root_min[a])) pool.fail(ei, "root corner not finite");
    if (!(info.root_size > 0.0f) || !std::isfinite(info.root_size) || !std::isfinite(1.0f / info.root_size))
        pool.fail(ei, "root edge not finite and positive");
    if (info.max_level > k_max_iso_level || info.min_level > info.max_level || info.depth > info.max_level)
        pool.fail(ei, "levels min " + std::to_string(info.min_level) + ", max " +
                          std::to_string(info.max_level) + ", depth " + std::to_string(info.depth) +
                          " are inconsistent or exceed " + std::to_string(k_max_iso_level));
}

/// Exactly the leaf arrays the flags name, each with leaf_count leaves.
void check_leaf_arrays(const PoolFile& pool, const SectionEntry* ei, const IsoSections& s) {
    const SectionEntry* eq = pool.find(SectionType::iso_leaves_q8);
    const SectionEntry* ef = pool.find(SectionType::iso_leaves_f32);
    const bool want_q8 = (s.info.flags & k_iso_has_q8) != 0, want_f32 = (s.info.flags & k_iso_has_f32) != 0;
    if (!want_q8 && !want_f32) pool.fail(ei, "flags name no leaf array");
    if (want_q8 != (eq != nullptr))
        pool.fail(eq ? eq : ei, want_q8 ? "section iso_leaves_q8 missing (iso_info's flags name it)"
                                        : "present but iso_info's flags do not name it");
    if (want_f32 != (ef != nullptr))
        pool.fail(ef ? ef : ei, want_f32 ? "section iso_leaves_f32 missing (iso_info's flags name it)"
                                         : "present but iso_info's flags do not name it");
    if (eq) detail::check_count(pool, eq, s.leaves_q8.size(), s.info.leaf_count, "leaves", "iso_info");
    if (ef) detail::check_count(pool, ef, s.leaves_f32.size(), s.info.leaf_count, "leaves", "iso_info");
}

}  // namespace

bool has_iso(const PoolFile& pool) {
    return detail::first_present(pool, k_iso_types) != nullptr;
}

IsoSections validate_iso(const PoolFile& pool) {
    detail::require_sections(pool, k_iso_types, 2, "the ISO needs iso_info and iso_nodes", "ISO");
    const SectionEntry* ei = pool.find(SectionType::iso_info);
    const SectionEntry* en = pool.find(SectionType::iso_nodes);
    IsoSections s;
    s.nodes = pool.array<std::uint32_t>(SectionType::iso_nodes);
    s.leaves_q8 = pool.array<IsoLeafQ8>(SectionType::iso_leaves_q8);
    s.leaves_f32 = pool.array<IsoLeafF32>(SectionType::iso_leaves_f32);
    s.info = detail::single<IsoInfo>(pool, SectionType::iso_info);
    check_iso_info(pool, ei, s.info);
    if (s.nodes.size() != s.info.node_count || s.nodes.empty())
        pool.fail(en, std::to_string(s.nodes.size()) + " nodes but iso_info says " +
                          std::to_string(s.info.node_count));
    check_leaf_arrays(pool, ei, s);
    // The tree: each child group after its parent and reached once, filled leaves addressing every
    // leaf exactly once, no internal node at max_level.
    const std::uint32_t deepest =
        detail::check_node_tree(pool, en, s.nodes, s.info.leaf_count, s.info.max_level, false);
    if (s.info.leaf_count > 0 && deepest != s.info.depth)
        pool.fail(en, "deepest filled leaf at level " + std::to_string(deepest) + " but iso_info says " +
                          std::to_string(s.info.depth));
    const SectionEntry* ef = pool.find(SectionType::iso_leaves_f32);
    for (std::size_t l = 0; l < s.leaves_f32.size(); ++l) {
        for (int c = 0; c < 8; ++c) {
            bool ok = std::isfinite(s.leaves_f32[l].value[c]);
            for (int a = 0; a < 3; ++a) ok = ok && std::isfinite(s.leaves_f32[l].normal[c][a]);
            if (!ok) pool.fail(ef, "leaf " + std::to_string(l) + ": value or normal not finite");
        }
    }
    return s;
}

}  // namespace prt::pool
