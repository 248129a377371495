// PointRT runtime (host): validation of the caustic and light-map sections (formats/POOL.md).
#include "prt/runtime/gi_pool.h"

#include <cmath>
#include <string>
#include <vector>

#include "prt/formats/gi_layout.h"

namespace prt::rt {

namespace {

struct Types {
    pool::SectionType info, nodes, leaves;
    const char* what;
};

core::GiOctreeView load_view(const pool::PoolFile& pool, const Types& t) {
    core::GiOctreeView v;
    const pool::SectionEntry* ei = pool.find(t.info);
    const pool::SectionEntry* en = pool.find(t.nodes);
    const pool::SectionEntry* el = pool.find(t.leaves);
    if (!ei && !en && !el) return v;
    if (!ei || !en || !el) {
        const pool::SectionEntry* any = ei ? ei : (en ? en : el);
        pool.fail(any, std::string("the ") + t.what + " needs " + pool::section_name(t.info) + ", " +
                           pool::section_name(t.nodes) + " and " + pool::section_name(t.leaves));
    }
    const auto infos = pool.array<pool::GiInfo>(t.info);
    const auto nodes = pool.array<std::uint32_t>(t.nodes);
    const auto leaves = pool.array<pool::GiLeaf>(t.leaves);
    if (infos.size() != 1) pool.fail(ei, "must hold exactly one element");
    const pool::GiInfo& info = infos[0];
    for (int a = 0; a < 3; ++a)
        if (!std::isfinite(info.root_min[a])) pool.fail(ei, "root corner not finite");
    if (!(std::isfinite(info.root_size) && info.root_size > 0.0f))
        pool.fail(ei, "root edge not finite and positive");
    if (info.depth > pool::k_max_gi_depth)
        pool.fail(ei,
                  "depth " + std::to_string(info.depth) + " above " + std::to_string(pool::k_max_gi_depth));
    if (info.node_count != nodes.size())
        pool.fail(
            en, std::to_string(nodes.size()) + " nodes but the info says " + std::to_string(info.node_count));
    if (info.leaf_count != leaves.size())
        pool.fail(el, std::to_string(leaves.size()) + " leaves but the info says " +
                          std::to_string(info.leaf_count));
    if (nodes.empty()) pool.fail(en, "no root node");
    if (!(std::isfinite(info.gather_radius) && info.gather_radius > 0.0f))
        pool.fail(ei, "gather radius not finite and positive");
    if (!(std::isfinite(info.scale) && info.scale > 0.0f))
        pool.fail(ei, "value scale not finite and positive");
    if (!(info.cos_threshold >= -1.0f && info.cos_threshold <= 1.0f))
        pool.fail(ei, "normal threshold outside [-1, 1]");
    // The nodes must form a tree from node 0: children after their parent, each node reached once,
    // filled leaves exactly at depth and each leaf addressed once.
    const std::size_t count = nodes.size();
    std::vector<std::uint8_t> level(count, 0), seen(count, 0);
    std::vector<std::uint8_t> leaf_seen(leaves.size(), 0);
    seen[0] = 1;
    std::size_t reached = 1;
    for (std::size_t i = 0; i < count; ++i) {
        if (!seen[i]) continue;
        const std::uint32_t w = nodes[i];
        const std::uint32_t a = pool::node_address(w);
        const std::string node = "node " + std::to_string(i) + ": ";
        switch (pool::node_type(w)) {
            case pool::NodeType::internal:
                if (level[i] >= info.depth)
                    pool.fail(en, node + "an internal node at the leaf level " + std::to_string(info.depth));
                if (a <= i || std::uint64_t(a) + 8 > count)
                    pool.fail(en, node + "children not after it or out of range");
                for (std::uint32_t c = 0; c < 8; ++c) {
                    if (seen[a + c])
                        pool.fail(en, node + "child " + std::to_string(a + c) + " has two parents");
                    seen[a + c] = 1;
                    level[a + c] = static_cast<std::uint8_t>(level[i] + 1);
                    ++reached;
                }
                break;
            case pool::NodeType::filled_leaf:
                if (level[i] != info.depth)
                    pool.fail(en, node + "filled leaf at level " + std::to_string(level[i]) + ", not " +
                                      std::to_string(info.depth));
                if (a >= leaves.size()) pool.fail(en, node + "leaf " + std::to_string(a) + " out of range");
                if (leaf_seen[a]++) pool.fail(en, node + "leaf " + std::to_string(a) + " addressed twice");
                break;
            case pool::NodeType::empty_leaf:
                break;
            default:
                pool.fail(en, node + "invalid node type 3");
        }
    }
    if (reached != count)
        pool.fail(en, std::to_string(count - reached) + " nodes not reachable from the root");
    for (std::size_t l = 0; l < leaves.size(); ++l)
        if (!leaf_seen[l]) pool.fail(en, "leaf " + std::to_string(l) + " is in no node");
    v.nodes = nodes.data();
    v.node_count = static_cast<std::uint32_t>(nodes.size());
    v.leaves = leaves.data();
    v.leaf_count = static_cast<std::uint32_t>(leaves.size());
    v.depth = info.depth;
    v.root_min = core::Vec3{info.root_min[0], info.root_min[1], info.root_min[2]};
    v.root_size = info.root_size;
    v.inv_root_size = 1.0f / info.root_size;
    v.scale = info.scale;
    v.cos_threshold = info.cos_threshold;
    return v;
}

const Types k_caustic{pool::SectionType::caustic_info, pool::SectionType::caustic_nodes,
                      pool::SectionType::caustic_leaves, "caustic octree"};
const Types k_light_map{pool::SectionType::light_map_info, pool::SectionType::light_map_nodes,
                        pool::SectionType::light_map_leaves, "light map"};

}  // namespace

bool has_caustics(const pool::PoolFile& pool) {
    return pool.has(k_caustic.info) || pool.has(k_caustic.nodes) || pool.has(k_caustic.leaves);
}

bool has_light_map(const pool::PoolFile& pool) {
    return pool.has(k_light_map.info) || pool.has(k_light_map.nodes) || pool.has(k_light_map.leaves);
}

core::CausticView load_caustic_view(const pool::PoolFile& pool) {
    return core::CausticView{load_view(pool, k_caustic)};
}

core::LightMapView load_light_map_view(const pool::PoolFile& pool) {
    return core::LightMapView{load_view(pool, k_light_map)};
}

}  // namespace prt::rt
