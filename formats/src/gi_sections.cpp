// PointRT pool file: validation of the caustic and light-map sections (gi_sections.h; rules in
// formats/POOL.md, "Caustics and light maps").
#include "prt/formats/gi_sections.h"

#include <cmath>
#include <string>

#include "section_checks.h"

namespace prt::pool {

namespace {

constexpr SectionType k_caustic_types[] = {SectionType::caustic_info, SectionType::caustic_nodes,
                                           SectionType::caustic_leaves};
constexpr SectionType k_light_map_types[] = {SectionType::light_map_info, SectionType::light_map_nodes,
                                             SectionType::light_map_leaves};

/// The root cube, depth and lookup parameters of one map's GiInfo.
void check_gi_info(const PoolFile& pool, const SectionEntry* ei, const GiInfo& info) {
    for (int a = 0; a < 3; ++a)
        if (!std::isfinite(info.root_min[a])) pool.fail(ei, "root corner not finite");
    if (!(std::isfinite(info.root_size) && info.root_size > 0.0f))
        pool.fail(ei, "root edge not finite and positive");
    if (info.depth > k_max_gi_depth)
        pool.fail(ei, "depth " + std::to_string(info.depth) + " above " + std::to_string(k_max_gi_depth));
}

/// One map: `types` are its info, nodes and leaves sections; `what` names it in errors.
std::optional<GiSections> validate_map(const PoolFile& pool, const SectionType (&types)[3],
                                       const char* what) {
    if (!detail::first_present(pool, types)) return std::nullopt;
    const std::string needs = std::string("the ") + what + " needs " + section_name(types[0]) + ", " +
                              section_name(types[1]) + " and " + section_name(types[2]);
    detail::require_sections(pool, types, 3, needs.c_str(), what);
    const SectionEntry* ei = pool.find(types[0]);
    const SectionEntry* en = pool.find(types[1]);
    GiSections s;
    s.info = detail::single<GiInfo>(pool, types[0]);
    s.nodes = pool.array<std::uint32_t>(types[1]);
    s.leaves = pool.array<GiLeaf>(types[2]);
    const GiInfo& info = s.info;
    check_gi_info(pool, ei, info);
    detail::check_count(pool, en, s.nodes.size(), info.node_count, "nodes", "the info");
    detail::check_count(pool, pool.find(types[2]), s.leaves.size(), info.leaf_count, "leaves", "the info");
    if (s.nodes.empty()) pool.fail(en, "no root node");
    if (!(std::isfinite(info.gather_radius) && info.gather_radius > 0.0f))
        pool.fail(ei, "gather radius not finite and positive");
    if (!(std::isfinite(info.scale) && info.scale > 0.0f))
        pool.fail(ei, "value scale not finite and positive");
    if (!(info.cos_threshold >= -1.0f && info.cos_threshold <= 1.0f))
        pool.fail(ei, "normal threshold outside [-1, 1]");
    // A tree from node 0 whose filled leaves all sit at depth, each leaf addressed exactly once.
    detail::check_node_tree(pool, en, s.nodes, info.leaf_count, info.depth, true);
    return s;
}

}  // namespace

bool has_caustics(const PoolFile& pool) {
    return detail::first_present(pool, k_caustic_types) != nullptr;
}

bool has_light_map(const PoolFile& pool) {
    return detail::first_present(pool, k_light_map_types) != nullptr;
}

std::optional<GiSections> validate_caustics(const PoolFile& pool) {
    return validate_map(pool, k_caustic_types, "caustic octree");
}

std::optional<GiSections> validate_light_map(const PoolFile& pool) {
    return validate_map(pool, k_light_map_types, "light map");
}

}  // namespace prt::pool
