// Test-only: walks a built splat octree and checks it against brute force, independently of the
// builder: layout (breadth first, 8 children together in Morton order), leaf ranges, splat records,
// and, with the polygon reference of disk_box_reference.h, that every leaf holds exactly the splats
// whose disk overlaps it (or, without replication, the splat whose centre it holds).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "disk_box_reference.h"
#include "octree_build.h"

namespace prt::test {

struct WalkedLeaf {
    std::uint32_t node;
    std::uint32_t level;
    double lo[3], hi[3];
    bool filled;
    std::uint32_t begin = 0, end = 0;  // splat range when filled
};

struct CheckSummary {
    std::vector<WalkedLeaf> leaves;
    std::uint64_t borderline = 0;  // leaf/splat pairs too close to the disk boundary to call
    std::uint64_t overlap_pairs = 0;
};

/// Box of a cell: root_min + root_size * cell / 2^level, computed here in long double.
inline void cell_box(const pool::OctreeInfo& info, std::uint32_t level, const std::uint64_t cell[3],
                     double lo[3], double hi[3]) {
    for (int a = 0; a < 3; ++a) {
        const long double s =
            static_cast<long double>(info.root_size) / static_cast<long double>(1ull << level);
        lo[a] = static_cast<double>(static_cast<long double>(info.root_min[a]) +
                                    s * static_cast<long double>(cell[a]));
        hi[a] = static_cast<double>(static_cast<long double>(info.root_min[a]) +
                                    s * static_cast<long double>(cell[a] + 1));
    }
}

/// Checks `octree` built from the given splats with `params`. Uses ADD_FAILURE/EXPECT so one call
/// reports every kind of problem; returns the walked leaves for further checks.
inline CheckSummary check_octree(const pre::SplatOctree& octree, std::span<const pool::Float3> positions,
                                 std::span<const pool::Float3> normals, std::span<const float> radii,
                                 const pre::OctreeParams& params) {
    CheckSummary out;
    const pool::OctreeInfo& info = octree.info;
    const auto& nodes = octree.nodes;
    // -- counts and leaf ranges ------------------------------------------------------------------
    EXPECT_EQ(info.node_count, nodes.size());
    EXPECT_EQ(std::size_t(info.filled_leaves) + 1, octree.leaf_info.size());
    EXPECT_EQ(info.splat_count, octree.splats.size());
    EXPECT_EQ(info.max_leaf_splats, params.max_leaf_splats);
    EXPECT_EQ((info.flags & pool::k_octree_replicated) != 0, params.replicate);
    if (octree.leaf_info.empty() || nodes.empty()) {
        ADD_FAILURE() << "empty octree";
        return out;
    }
    EXPECT_EQ(octree.leaf_info.front(), 0u);
    EXPECT_EQ(octree.leaf_info.back(), octree.splats.size());
    for (std::size_t i = 0; i + 1 < octree.leaf_info.size(); ++i)
        EXPECT_LT(octree.leaf_info[i], octree.leaf_info[i + 1])
            << "filled leaf " << i << " is empty or inverted";

    // -- layout: breadth first, children contiguous; internal node k (in index order) has its
    //    children at 1 + 8k exactly when nodes are stored level by level with no gaps ------------
    std::uint64_t internal_rank = 0;
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        if (pool::node_type(nodes[i]) == pool::NodeType::internal) {
            EXPECT_EQ(pool::node_address(nodes[i]), 1 + 8 * internal_rank) << "node " << i;
            ++internal_rank;
        } else if (pool::node_type(nodes[i]) == pool::NodeType::empty_leaf) {
            EXPECT_EQ(pool::node_address(nodes[i]), 0u) << "empty leaf " << i;
        } else if (pool::node_type(nodes[i]) != pool::NodeType::filled_leaf) {
            ADD_FAILURE() << "node " << i << ": invalid type";
        }
    }
    EXPECT_EQ(nodes.size(), 1 + 8 * internal_rank);

    // -- walk from the root with the Morton child convention c = x | y << 1 | z << 2 ---------------
    struct Item {
        std::uint32_t node, level;
        std::uint64_t cell[3];
    };
    std::vector<Item> queue{{0, 0, {0, 0, 0}}};
    std::vector<std::uint32_t> level_of(nodes.size(), ~0u);
    std::vector<int> leaf_seen(info.filled_leaves, 0);
    std::uint32_t max_level = 0;
    for (std::size_t q = 0; q < queue.size(); ++q) {
        const Item it = queue[q];
        if (it.node >= nodes.size()) {
            ADD_FAILURE() << "node address " << it.node << " out of range";
            continue;
        }
        if (level_of[it.node] != ~0u) {
            ADD_FAILURE() << "node " << it.node << " reached twice";
            continue;
        }
        level_of[it.node] = it.level;
        max_level = std::max(max_level, it.level);
        const std::uint32_t word = nodes[it.node];
        if (pool::node_type(word) == pool::NodeType::internal) {
            EXPECT_LT(it.level, params.max_depth) << "internal node below the maximum depth";
            // the subdivision rule: an internal node holds more than X splats (replicas included)
            double lo[3], hi[3];
            cell_box(info, it.level, it.cell, lo, hi);
            std::uint64_t held = 0;
            for (std::size_t p = 0; p < positions.size(); ++p) {
                if (!(radii[p] > 0) || !std::isfinite(radii[p])) continue;
                const double c[3] = {positions[p].x, positions[p].y, positions[p].z};
                const double n[3] = {normals[p].x, normals[p].y, normals[p].z};
                if (params.replicate && !params.split_by_centres) {
                    bool near = true;
                    for (int a = 0; a < 3; ++a)
                        near = near && c[a] + radii[p] >= lo[a] && c[a] - radii[p] <= hi[a];
                    if (near && reference_disk_box_overlap(c, n, radii[p], lo, hi) >= 0) ++held;
                } else {
                    bool inside = true;
                    for (int a = 0; a < 3; ++a) inside = inside && c[a] >= lo[a] && c[a] < hi[a];
                    if (inside) ++held;
                }
            }
            EXPECT_GT(held, params.max_leaf_splats)
                << "node " << it.node << " was split holding only " << held;
            const std::uint32_t a = pool::node_address(word);
            for (std::uint32_t c = 0; c < 8; ++c)
                queue.push_back({a + c,
                                 it.level + 1,
                                 {2 * it.cell[0] + (c & 1), 2 * it.cell[1] + ((c >> 1) & 1),
                                  2 * it.cell[2] + ((c >> 2) & 1)}});
        } else {
            WalkedLeaf leaf{};
            leaf.node = it.node;
            leaf.level = it.level;
            cell_box(info, it.level, it.cell, leaf.lo, leaf.hi);
            leaf.filled = pool::node_type(word) == pool::NodeType::filled_leaf;
            if (leaf.filled) {
                const std::uint32_t a = pool::node_address(word);
                if (a >= info.filled_leaves) {
                    ADD_FAILURE() << "leaf address " << a << " out of range";
                    continue;
                }
                ++leaf_seen[a];
                leaf.begin = octree.leaf_info[a];
                leaf.end = octree.leaf_info[a + 1];
            }
            out.leaves.push_back(leaf);
        }
    }
    EXPECT_EQ(queue.size(), nodes.size()) << "nodes not reachable from the root";
    for (std::size_t i = 1; i < nodes.size(); ++i)
        EXPECT_LE(level_of[i - 1], level_of[i]) << "nodes not breadth first at " << i;
    for (std::size_t a = 0; a < leaf_seen.size(); ++a) EXPECT_EQ(leaf_seen[a], 1) << "leaf_info entry " << a;
    EXPECT_EQ(info.depth, max_level);

    // -- splat records -------------------------------------------------------------------------------
    std::vector<std::uint64_t> stored_of(positions.size(), 0);
    std::uint64_t valid = 0;
    for (std::size_t i = 0; i < positions.size(); ++i)
        if (radii[i] > 0 && std::isfinite(radii[i])) ++valid;
    EXPECT_EQ(info.unique_splats, valid);
    for (const pool::Splat& s : octree.splats) {
        if (s.point >= positions.size()) {
            ADD_FAILURE() << "splat point index out of range";
            continue;
        }
        ++stored_of[s.point];
        EXPECT_EQ(s.position.x, positions[s.point].x);
        EXPECT_EQ(s.position.y, positions[s.point].y);
        EXPECT_EQ(s.position.z, positions[s.point].z);
        EXPECT_EQ(s.radius, radii[s.point]);
        const pool::Float3& n = normals[s.point];
        const double len = std::sqrt(double(n.x) * n.x + double(n.y) * n.y + double(n.z) * n.z);
        EXPECT_NEAR(s.normal.x, n.x / len, 1e-6);
        EXPECT_NEAR(s.normal.y, n.y / len, 1e-6);
        EXPECT_NEAR(s.normal.z, n.z / len, 1e-6);
    }
    for (std::size_t i = 0; i < positions.size(); ++i) {
        const bool usable = radii[i] > 0 && std::isfinite(radii[i]);
        if (!usable)
            EXPECT_EQ(stored_of[i], 0u) << "point " << i << " without a radius was stored";
        else if (!params.replicate)
            EXPECT_EQ(stored_of[i], 1u) << "point " << i;
        else
            EXPECT_GE(stored_of[i], 1u) << "point " << i;
    }

    // -- membership against brute force ---------------------------------------------------------
    for (const WalkedLeaf& leaf : out.leaves) {
        std::set<std::uint32_t> members;
        for (std::uint32_t k = leaf.begin; k < leaf.end; ++k) {
            const bool fresh = members.insert(octree.splats[k].point).second;
            EXPECT_TRUE(fresh) << "splat " << octree.splats[k].point << " twice in leaf node " << leaf.node;
        }
        std::uint64_t overlapping = 0, centres = 0;
        double radius_sum = 0;
        for (std::uint32_t p = 0; p < positions.size(); ++p) {
            if (!(radii[p] > 0) || !std::isfinite(radii[p])) continue;
            const double c[3] = {positions[p].x, positions[p].y, positions[p].z};
            const double n[3] = {normals[p].x, normals[p].y, normals[p].z};
            const double r = radii[p];
            bool expected_in;
            if (params.replicate) {
                // cheap independent reject: the bounding cube c +- r
                bool near = true;
                for (int a = 0; a < 3; ++a) near = near && c[a] + r >= leaf.lo[a] && c[a] - r <= leaf.hi[a];
                int call = near ? reference_disk_box_overlap(c, n, r, leaf.lo, leaf.hi) : -1;
                // the centre's own leaf (closed box) always holds it
                bool centre_in = true;
                for (int a = 0; a < 3; ++a) centre_in = centre_in && c[a] >= leaf.lo[a] && c[a] <= leaf.hi[a];
                if (centre_in) call = 1;
                if (call == 0) {
                    ++out.borderline;
                    if (members.count(p)) {
                        ++overlapping;
                        radius_sum += r;
                    }
                    continue;
                }
                expected_in = call > 0;
            } else {
                // half-open cells, upper child on a tie: the leaf holding the centre
                bool inside = true;
                for (int a = 0; a < 3; ++a) inside = inside && c[a] >= leaf.lo[a] && c[a] < leaf.hi[a];
                expected_in = inside;
            }
            if (expected_in) {
                ++overlapping;
                radius_sum += r;
                ++out.overlap_pairs;
            }
            bool centre_half_open = true;
            for (int a = 0; a < 3; ++a)
                centre_half_open = centre_half_open && c[a] >= leaf.lo[a] && c[a] < leaf.hi[a];
            centres += centre_half_open;
            const bool stored = members.count(p) != 0;
            if (expected_in != stored) {
                ADD_FAILURE() << "splat " << p << (expected_in ? " missing from" : " wrongly in")
                              << " leaf node " << leaf.node << " (level " << leaf.level << ")";
                if (out.borderline > 1000000) return out;  // unreachable guard against a flood
            }
        }
        // the subdivision rule: a leaf holds more than X splats (or centres, with split_by_centres)
        // only where splitting stopped
        const std::uint64_t rule_count = params.split_by_centres ? centres : overlapping;
        if (rule_count > params.max_leaf_splats) {
            const double edge = leaf.hi[0] - leaf.lo[0];
            const bool at_max = leaf.level >= params.max_depth;
            const bool small = params.min_cell_ratio > 0 &&
                               edge < params.min_cell_ratio * radius_sum / double(overlapping) * (1 + 1e-9);
            EXPECT_TRUE(at_max || small)
                << "leaf node " << leaf.node << " holds " << rule_count << " splats but was not split";
        }
    }
    return out;
}

}  // namespace prt::test
