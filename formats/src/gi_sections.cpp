// PointRT pool file: validation of the caustic and light-map sections (gi_sections.h; rules in
// formats/POOL.md, "Caustics and light maps").
#include "prt/formats/gi_sections.h"

#include <cmath>
#include <string>

#include "section_checks.h"
#include "xxhash_inline.h"

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

/// Map `index` of a pool's maps, whose arrays are nodes[node_begin..] and leaves[leaf_begin..].
GiSections check_map(const PoolFile& pool, const SectionType (&types)[3], const GiInfo& info,
                     std::span<const std::uint32_t> all_nodes, std::span<const GiLeaf> all_leaves,
                     std::uint64_t node_begin, std::uint64_t leaf_begin, const std::string& where) {
    const SectionEntry* ei = pool.find(types[0]);
    const SectionEntry* en = pool.find(types[1]);
    GiSections s;
    s.info = info;
    check_gi_info(pool, ei, info);
    const std::uint64_t node_end = node_begin + info.node_count, leaf_end = leaf_begin + info.leaf_count;
    if (node_end > all_nodes.size())
        pool.fail(en, where + "the infos say " + std::to_string(node_end) + " nodes, the section holds " +
                          std::to_string(all_nodes.size()));
    if (leaf_end > all_leaves.size())
        pool.fail(pool.find(types[2]), where + "the infos say " + std::to_string(leaf_end) +
                                           " leaves, the section holds " + std::to_string(all_leaves.size()));
    s.nodes = all_nodes.subspan(node_begin, info.node_count);
    s.leaves = all_leaves.subspan(leaf_begin, info.leaf_count);
    if (s.nodes.empty()) pool.fail(en, where + "no root node");
    if (!(std::isfinite(info.gather_radius) && info.gather_radius > 0.0f))
        pool.fail(ei, "gather radius not finite and positive");
    if (!(std::isfinite(info.scale) && info.scale > 0.0f))
        pool.fail(ei, "value scale not finite and positive");
    if (!(info.cos_threshold >= -1.0f && info.cos_threshold <= 1.0f))
        pool.fail(ei, "normal threshold outside [-1, 1]");
    // A tree from node 0 whose filled leaves all sit at depth, each leaf addressed exactly once.
    detail::check_node_tree(pool, en, s.nodes, info.leaf_count, info.depth, true, where);
    return s;
}

/// Every map of one family: `types` are its info, nodes and leaves sections; `what` names it in
/// errors; `several`: the info section may hold more than one map (one per placement).
std::vector<GiSections> validate_maps(const PoolFile& pool, const SectionType (&types)[3], const char* what,
                                      bool several) {
    std::vector<GiSections> maps;
    if (!detail::first_present(pool, types)) return maps;
    const std::string needs = std::string("the ") + what + " needs " + section_name(types[0]) + ", " +
                              section_name(types[1]) + " and " + section_name(types[2]);
    detail::require_sections(pool, types, 3, needs.c_str(), what);
    const std::span<const GiInfo> infos =
        several ? pool.array<GiInfo>(types[0])
                : std::span<const GiInfo>(&detail::single<GiInfo>(pool, types[0]), 1);
    if (infos.empty()) pool.fail(pool.find(types[0]), "holds no map");
    const std::span<const std::uint32_t> nodes = pool.array<std::uint32_t>(types[1]);
    const std::span<const GiLeaf> leaves = pool.array<GiLeaf>(types[2]);
    std::uint64_t node_begin = 0, leaf_begin = 0;
    for (std::size_t k = 0; k < infos.size(); ++k) {
        const std::string where = infos.size() > 1 ? "map " + std::to_string(k) + ": " : "";
        maps.push_back(check_map(pool, types, infos[k], nodes, leaves, node_begin, leaf_begin, where));
        node_begin += infos[k].node_count;
        leaf_begin += infos[k].leaf_count;
        if (infos.size() > 1) {
            if (infos[k].placement == 0)
                pool.fail(pool.find(types[0]), where + "placement key 0 among several maps");
            for (std::size_t j = 0; j < k; ++j)
                if (infos[j].placement == infos[k].placement)
                    pool.fail(pool.find(types[0]), where + "the placement key of map " + std::to_string(j));
        }
    }
    detail::check_count(pool, pool.find(types[1]), nodes.size(), node_begin, "nodes", "the infos");
    detail::check_count(pool, pool.find(types[2]), leaves.size(), leaf_begin, "leaves", "the infos");
    return maps;
}

}  // namespace

bool has_caustics(const PoolFile& pool) {
    return detail::first_present(pool, k_caustic_types) != nullptr;
}

bool has_light_map(const PoolFile& pool) {
    return detail::first_present(pool, k_light_map_types) != nullptr;
}

std::uint32_t placement_key(const scene::Transform& t) {
    const double v[7] = {t.translate[0],      t.translate[1],      t.translate[2], t.rotate_degrees[0],
                         t.rotate_degrees[1], t.rotate_degrees[2], t.scale};
    const std::uint64_t h = XXH3_64bits(v, sizeof v);
    const std::uint32_t key = static_cast<std::uint32_t>(h ^ (h >> 32));
    return key != 0 ? key : 1u;
}

std::vector<GiSections> validate_caustic_maps(const PoolFile& pool) {
    return validate_maps(pool, k_caustic_types, "caustic octree", true);
}

std::vector<GiSections> validate_light_maps(const PoolFile& pool) {
    return validate_maps(pool, k_light_map_types, "light map", true);
}

const GiSections* find_gi_map(const std::vector<GiSections>& maps, std::uint32_t placement) {
    for (const GiSections& m : maps)
        if (m.info.placement == placement) return &m;
    for (const GiSections& m : maps)
        if (m.info.placement == 0) return &m;
    return nullptr;
}

std::optional<GiSections> validate_caustics(const PoolFile& pool) {
    std::vector<GiSections> maps = validate_maps(pool, k_caustic_types, "caustic octree", false);
    if (maps.empty()) return std::nullopt;
    return maps[0];
}

std::optional<GiSections> validate_light_map(const PoolFile& pool) {
    std::vector<GiSections> maps = validate_maps(pool, k_light_map_types, "light map", false);
    if (maps.empty()) return std::nullopt;
    return maps[0];
}

}  // namespace prt::pool
