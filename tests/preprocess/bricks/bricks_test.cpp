// The brick builder (preprocess/bricks, issue 17) and the brick validation (brick_sections.h):
// a bricked pool validates; every float splat is found, decoded within the codec's bounds, in the
// brick reached by an independent walk of both trees; LOD discs cover their subtrees; corrupted
// and inconsistent pools are refused naming the brick; prt-bricks writes nothing on bad input.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "brick_build.h"
#include "bricks_test_data.h"
#include "octree_build.h"
#include "point_cloud.h"
#include "preprocess/splat/splat_test_data.h"
#include "prt/formats/brick_sections.h"
#include "prt/formats/octree_sections.h"
#include "prt/formats/pool.h"
#include "radii.h"
#include "runtime/tool_run.h"

namespace {

namespace fs = std::filesystem;
using namespace prt;
using pool::NodeType;
using pool::PoolFile;
using pool::SectionType;
using test::bricked_bytes;
using test::octree_pool_bytes;

constexpr double k_pi = 3.14159265358979323846;

class Bricks : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        s_octree = new PoolFile(PoolFile::from_bytes(octree_pool_bytes(6000), "octree"));
        s_bricked = new PoolFile(PoolFile::from_bytes(bricked_bytes(*s_octree, 700, &s_stats), "bricked"));
    }
    static void TearDownTestSuite() {
        delete s_bricked;
        delete s_octree;
    }
    static PoolFile* s_octree;
    static PoolFile* s_bricked;
    static pre::BrickStats s_stats;
};
PoolFile* Bricks::s_octree = nullptr;
PoolFile* Bricks::s_bricked = nullptr;
pre::BrickStats Bricks::s_stats;

TEST_F(Bricks, BrickedPoolValidates) {
    const pool::BrickSections b = pool::validate_bricks(*s_bricked);
    const pool::SplatOctreeSections f = pool::splat_octree(*s_octree, "test");
    EXPECT_GT(b.info.brick_count, 8u);  // the cut made many bricks, so the top tree is not trivial
    EXPECT_EQ(b.info.splat_count, f.splats.size());
    std::uint64_t sum = 0;
    for (const pool::BrickEntry& e : b.table) {
        sum += e.splat_count;
        EXPECT_EQ(e.offset % 64, 0u);
        // at most N splats, unless the brick is a single leaf
        if (e.splat_count > 700) {
            EXPECT_EQ(e.node_count, 1u);
        }
    }
    EXPECT_EQ(sum, f.splats.size());
    EXPECT_EQ(b.info.flags & pool::k_bricks_colors, pool::k_bricks_colors);
    EXPECT_EQ(b.info.flags & pool::k_bricks_indexed, pool::k_bricks_indexed);
    // each point once per brick that holds it: the encoded splats are the distinct (brick, point)
    // pairs, counted here from the float leaves independently of the builder
    // (a direct brick, BrickParams::Direct::smaller, stores one record per reference instead)
    std::uint64_t distinct = 0;
    std::uint32_t direct = 0;
    for (std::uint32_t bi = 0; bi < b.table.size(); ++bi) {
        const pool::BrickView v = pool::brick_view(b.payload(bi));
        std::set<std::tuple<std::uint16_t, std::uint16_t, std::uint16_t, std::uint32_t>> seen;
        for (const pool::CompressedSplat& c : v.splats) seen.insert({c.q[0], c.q[1], c.q[2], c.nr});
        if (pool::brick_is_direct(*v.header)) {
            ++direct;
            EXPECT_EQ(v.ref_bytes, 0u);
            EXPECT_EQ(v.splats.size(), b.table[bi].splat_count);
            distinct += v.splats.size();
            continue;
        }
        EXPECT_EQ(v.ref_bytes, 2u);
        distinct += seen.size();  // no two encoded splats of a brick alike
        EXPECT_EQ(seen.size(), v.splats.size());
    }
    EXPECT_EQ(direct, s_stats.direct_bricks);
    EXPECT_LT(direct, b.info.brick_count);  // this tree is replicated: most bricks reference
    EXPECT_EQ(distinct, b.info.encoded_splats);
    EXPECT_LT(b.info.encoded_splats, b.info.splat_count);  // replicas share their encoded splat
    // 12 B per distinct splat, 2 B per reference, nodes and leaf ranges: well under the float
    // layout's 32 B per reference
    EXPECT_LT(double(b.data.size()) / double(f.splats.size()), 12.0);
}

/// Child index paths of every filled leaf of a node tree, with the leaf's address.
void leaf_paths(std::span<const std::uint32_t> nodes, std::uint32_t i, std::vector<std::uint8_t>& path,
                const std::function<void(const std::vector<std::uint8_t>&, std::uint32_t)>& f) {
    const std::uint32_t w = nodes[i];
    if (pool::node_type(w) == NodeType::filled_leaf) f(path, pool::node_address(w));
    if (pool::node_type(w) != NodeType::internal) return;
    for (std::uint8_t c = 0; c < 8; ++c) {
        path.push_back(c);
        leaf_paths(nodes, pool::node_address(w) + c, path, f);
        path.pop_back();
    }
}

TEST_F(Bricks, EveryFloatSplatIsInTheBrickCoveringItsLeafDecodedWithinBounds) {
    const pool::BrickSections b = pool::validate_bricks(*s_bricked);
    const pool::SplatOctreeSections f = pool::splat_octree(*s_octree, "test");
    const auto colors = s_octree->array<pool::Rgba8>(SectionType::colors);
    const double normal_bound = 3.0 * (std::sqrt(2.0) / 2.0 / 511.0) * 180.0 / k_pi + 1e-4;
    std::uint64_t found = 0;
    std::vector<std::uint8_t> path;
    leaf_paths(f.nodes, 0, path, [&](const std::vector<std::uint8_t>& p, std::uint32_t leaf) {
        // down the top tree to a brick
        std::uint32_t t = 0;
        std::size_t k = 0;
        while (pool::node_type(b.top_nodes[t]) == NodeType::internal) {
            ASSERT_LT(k, p.size());
            t = pool::node_address(b.top_nodes[t]) + p[k++];
        }
        ASSERT_EQ(pool::node_type(b.top_nodes[t]), NodeType::brick)
            << "leaf " << leaf << " under a non-brick";
        const std::uint32_t bi = pool::node_address(b.top_nodes[t]);
        EXPECT_EQ(b.table[bi].level, k);
        const pool::BrickView v = pool::brick_view(b.payload(bi));
        // down the brick's own nodes along the rest of the path
        std::uint32_t n = 0;
        for (; k < p.size(); ++k) {
            ASSERT_EQ(pool::node_type(v.nodes[n]), NodeType::internal);
            n = pool::node_address(v.nodes[n]) + p[k];
        }
        ASSERT_EQ(pool::node_type(v.nodes[n]), NodeType::filled_leaf);
        const std::uint32_t l = pool::node_address(v.nodes[n]);
        const std::uint32_t fb = f.leaf_info[leaf], fe = f.leaf_info[leaf + 1];
        ASSERT_EQ(v.leaf_info[l + 1] - v.leaf_info[l], fe - fb);
        const pool::BrickHeader& h = *v.header;
        const double quantum = double(h.quant_size) / 65535.0;
        const double slack =
            4e-7 * (std::fabs(h.quant_min[0]) + std::fabs(h.quant_min[1]) + h.quant_size + 16);
        for (std::uint32_t i = 0; i < fe - fb; ++i) {
            const pool::Splat& s = f.splats[fb + i];
            const pool::DecodedSplat d = pool::decode_splat(v.splats[v.ref(v.leaf_info[l] + i)], h);
            EXPECT_LE(std::fabs(d.position.x - s.position.x), 0.5 * quantum + slack);
            EXPECT_LE(std::fabs(d.position.y - s.position.y), 0.5 * quantum + slack);
            EXPECT_LE(std::fabs(d.position.z - s.position.z), 0.5 * quantum + slack);
            EXPECT_GE(d.radius, s.radius);
            EXPECT_LE(d.radius, s.radius * std::exp2(1.0 / 128.0) * (1 + 4e-6));
            const double dot = double(d.normal.x) * s.normal.x + double(d.normal.y) * s.normal.y +
                               double(d.normal.z) * s.normal.z;
            EXPECT_LE(std::acos(std::min(1.0, dot)) * 180.0 / k_pi, normal_bound);
            const pool::Rgba8 c = colors[s.point];
            EXPECT_LE(std::abs(int(d.color.r) - c.r), 4);
            EXPECT_LE(std::abs(int(d.color.g) - c.g), 2);
            EXPECT_LE(std::abs(int(d.color.b) - c.b), 4);
            ++found;
        }
    });
    EXPECT_EQ(found, f.splats.size());
    // the builder's own measurement (over each encoded splat) agrees with the bounds
    EXPECT_EQ(s_stats.error.splats, s_stats.encoded);
    EXPECT_LE(s_stats.error.normal_max_deg, normal_bound);
    EXPECT_EQ(s_stats.error.radius_shrink_max, 0.0);
}

TEST_F(Bricks, LodDiscsCoverTheirSubtrees) {
    const pool::BrickSections b = pool::validate_bricks(*s_bricked);
    const pool::SplatOctreeSections f = pool::splat_octree(*s_octree, "test");
    std::uint32_t checked = 0;
    // walk the top tree and the float tree together; returns the float splat indices below
    std::function<std::vector<std::uint32_t>(std::uint32_t, std::uint32_t)> walk = [&](std::uint32_t t,
                                                                                       std::uint32_t s) {
        std::vector<std::uint32_t> below;
        if (pool::node_type(b.top_nodes[t]) == NodeType::internal) {
            EXPECT_EQ(pool::node_type(f.nodes[s]), NodeType::internal);
            for (std::uint32_t c = 0; c < 8; ++c) {
                const auto sub =
                    walk(pool::node_address(b.top_nodes[t]) + c, pool::node_address(f.nodes[s]) + c);
                below.insert(below.end(), sub.begin(), sub.end());
            }
        } else if (pool::node_type(b.top_nodes[t]) == NodeType::brick) {
            std::vector<std::uint8_t> path;
            leaf_paths(f.nodes, s, path, [&](const std::vector<std::uint8_t>&, std::uint32_t leaf) {
                for (std::uint32_t i = f.leaf_info[leaf]; i < f.leaf_info[leaf + 1]; ++i) below.push_back(i);
            });
        }
        const pool::LodSplat& d = b.lod[t];
        if (below.empty()) {
            EXPECT_EQ(d.radius, 0.0f);
            return below;
        }
        EXPECT_NEAR(double(d.normal.x) * d.normal.x + double(d.normal.y) * d.normal.y +
                        double(d.normal.z) * d.normal.z,
                    1.0, 1e-5);
        for (const std::uint32_t i : below) {
            const pool::Splat& sp = f.splats[i];
            const double dx = double(sp.position.x) - d.position.x, dy = double(sp.position.y) - d.position.y,
                         dz = double(sp.position.z) - d.position.z;
            EXPECT_LE(std::sqrt(dx * dx + dy * dy + dz * dz) + sp.radius, double(d.radius) * (1 + 1e-9))
                << "top node " << t << " splat " << i;
        }
        ++checked;
        return below;
    };
    walk(0, 0);
    EXPECT_GT(checked, b.info.brick_count);  // bricks and inner nodes
}

TEST(BricksCut, ExtremeBrickSizes) {
    const PoolFile in = PoolFile::from_bytes(octree_pool_bytes(1500), "octree");
    // N = 1: every filled leaf is a brick of its own (more than N splats there)
    const PoolFile one = PoolFile::from_bytes(bricked_bytes(in, 1), "one");
    const pool::BrickSections b1 = pool::validate_bricks(one);
    EXPECT_EQ(b1.info.brick_count, pool::splat_octree(in, "t").info.filled_leaves);
    // N huge: the root is the one brick
    const PoolFile all = PoolFile::from_bytes(bricked_bytes(in, 0xFFFFFFFFu), "all");
    const pool::BrickSections ba = pool::validate_bricks(all);
    EXPECT_EQ(ba.info.brick_count, 1u);
    EXPECT_EQ(ba.info.top_node_count, 1u);
    EXPECT_EQ(ba.table[0].node_count, pool::splat_octree(in, "t").info.node_count);
}

TEST(BricksRealData, KittenScanBricksWithinTheCodecBounds) {
    const fs::path file = fs::path(PRT_SHARED_DATA_DIR) / "points/cgal_kitten/kitten.xyz";
    if (!fs::exists(file)) GTEST_SKIP() << "shared data not present: " << file;
    pre::PointCloud cloud;
    std::ifstream in(file);
    double x, y, z, nx, ny, nz;
    std::vector<pool::Float3> local;
    while (in >> x >> y >> z >> nx >> ny >> nz) {
        cloud.positions.push_back({x, y, z});
        cloud.normals.push_back({float(nx), float(ny), float(nz)});
        local.push_back({float(x), float(y), float(z)});
    }
    ASSERT_EQ(cloud.size(), 5210u);
    // radii: distance to the 8th nearest neighbour (thesis 3.1), brute force
    for (const double r : test::brute_force_knn(local, 8)) cloud.radii.push_back(float(r));
    const PoolFile octree = PoolFile::from_bytes(octree_pool_bytes(cloud, 48), "kitten");
    pre::BrickStats stats;
    const PoolFile bricked = PoolFile::from_bytes(bricked_bytes(octree, 2048, &stats), "kitten bricks");
    const pool::BrickSections b = pool::validate_bricks(bricked);
    EXPECT_GT(b.info.brick_count, 4u);
    EXPECT_EQ(b.info.splat_count, pool::splat_octree(octree, "t").splats.size());
    const double normal_bound = 3.0 * (std::sqrt(2.0) / 2.0 / 511.0) * 180.0 / k_pi + 1e-4;
    EXPECT_LE(stats.error.normal_max_deg, normal_bound);
    EXPECT_EQ(stats.error.radius_shrink_max, 0.0);
    EXPECT_LE(stats.error.radius_growth_max, std::exp2(1.0 / 128.0) - 1.0 + 1e-5);
    EXPECT_LE(stats.error.position_quanta_max, 0.6);
    std::printf(
        "kitten: %u bricks, %llu splats; position max %.5f radii, normal max %.3f deg, radius growth max "
        "%.4f\n",
        b.info.brick_count, static_cast<unsigned long long>(stats.splats), stats.error.position_max,
        stats.error.normal_max_deg, stats.error.radius_growth_max);
}

// ---- bad input ------------------------------------------------------------------------------------

/// `good` with some brick sections replaced by modified copies (checksums recomputed by the writer).
PoolFile modified(const PoolFile& good,
                  const std::function<void(pool::BrickInfo&, std::vector<pool::BrickEntry>&,
                                           std::vector<std::byte>&)>& change) {
    const pool::BrickSections s = pool::validate_bricks(good);
    pool::BrickInfo info = s.info;
    std::vector<pool::BrickEntry> table(s.table.begin(), s.table.end());
    std::vector<std::byte> data(s.data.begin(), s.data.end());
    change(info, table, data);
    pool::PoolWriter w;
    w.carry_over(good);
    w.add_array(SectionType::brick_info, std::vector<pool::BrickInfo>{info});
    w.add_array(SectionType::brick_table, std::move(table));
    w.add_array(SectionType::brick_data, std::move(data));
    return PoolFile::from_bytes(w.serialize(), "bad.pool");
}

std::string error_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

TEST_F(Bricks, CorruptedBrickIsRefusedNamingIt) {
    const std::uint32_t victim = 3;
    const PoolFile bad = modified(*s_bricked, [&](auto&, auto& table, auto& data) {
        data[table[victim].offset + table[victim].size - 5] ^= std::byte{0x10};  // one splat byte
    });
    const std::string e = error_of([&] { pool::validate_bricks(bad); });
    EXPECT_EQ(e, "bad.pool: section brick_data: brick 3: checksum mismatch");
    // the other bricks still validate alone (streaming reads them one by one)
    const pool::BrickSections s = pool::validate_brick_index(bad);
    for (std::uint32_t b = 0; b < s.table.size(); ++b)
        if (b != victim) {
            EXPECT_NO_THROW(pool::validate_brick(bad, s, b, s.payload(b)));
        }
    // a brick read alone with a wrong length
    EXPECT_NE(error_of([&] {
                  pool::validate_brick(bad, s, 1, s.payload(1).first(40));
              }).find("brick 1: 40 bytes but its entry says"),
              std::string::npos);
}

TEST_F(Bricks, StreamingOpenDefersTheBrickChecksumsToEachBrick) {
    // A pool file with one byte of brick 3 flipped, the way a disk would corrupt it (the section's
    // checksum is stale). A normal open refuses the whole pool; a streaming open defers brick_data's
    // checksum, so the pool opens and only brick 3 is refused when it is read.
    const std::uint32_t victim = 3;
    const pool::BrickSections good = pool::validate_bricks(*s_bricked);
    std::vector<std::byte> bytes(s_bricked->file_bytes().begin(), s_bricked->file_bytes().end());
    const std::uint64_t at = s_bricked->find(SectionType::brick_data)->offset + good.table[victim].offset +
                             good.table[victim].size - 5;
    bytes[at] ^= std::byte{0x10};
    EXPECT_NE(error_of([&] {
                  PoolFile::from_bytes(bytes, "disk.pool");
              }).find("disk.pool: section brick_data: bad checksum (file corrupted)"),
              std::string::npos);
    pool::OpenOptions streaming;
    streaming.defer_brick_payloads = true;
    const PoolFile pool = PoolFile::from_bytes(bytes, "disk.pool", streaming);
    const pool::BrickSections s = pool::validate_brick_index(pool);
    for (std::uint32_t b = 0; b < s.table.size(); ++b) {
        const std::string e = error_of([&] { pool::validate_brick(pool, s, b, s.payload(b)); });
        EXPECT_EQ(e, b == victim ? "disk.pool: section brick_data: brick 3: checksum mismatch" : "") << b;
    }
    // Deferring skips brick_data only: a flipped byte in any other section is still refused at open.
    std::vector<std::byte> top(s_bricked->file_bytes().begin(), s_bricked->file_bytes().end());
    top[s_bricked->find(SectionType::brick_top_nodes)->offset] ^= std::byte{0x01};
    EXPECT_NE(error_of([&] {
                  PoolFile::from_bytes(top, "disk.pool", streaming);
              }).find("section brick_top_nodes: bad checksum"),
              std::string::npos);
}

TEST_F(Bricks, MoreBricksClaimedThanHeldIsRefused) {
    const PoolFile bad = modified(*s_bricked, [](auto& info, auto&, auto&) { info.brick_count += 1; });
    const std::string e = error_of([&] { pool::validate_brick_index(bad); });
    EXPECT_NE(e.find("section brick_table: "), std::string::npos) << e;
    EXPECT_NE(e.find("bricks but brick_info says"), std::string::npos) << e;
}

TEST_F(Bricks, OverlappingOrMisplacedPayloadsAreRefused) {
    const PoolFile overlap = modified(*s_bricked, [](auto&, auto& table, auto&) {
        table[2].offset = table[1].offset;  // same size class not needed: any overlap is refused
    });
    const std::string e = error_of([&] { pool::validate_brick_index(overlap); });
    EXPECT_NE(e.find("overlaps"), std::string::npos) << e;
    const PoolFile unaligned = modified(*s_bricked, [](auto&, auto& table, auto&) { table[4].offset += 4; });
    EXPECT_NE(error_of([&] { pool::validate_brick_index(unaligned); }).find("brick 4: offset"),
              std::string::npos);
    const PoolFile outside = modified(
        *s_bricked, [](auto&, auto& table, auto& data) { table[0].offset = (data.size() + 64) / 64 * 64; });
    EXPECT_NE(error_of([&] { pool::validate_brick_index(outside); }).find("brick 0: payload"),
              std::string::npos);
    const PoolFile counts =
        modified(*s_bricked, [](auto&, auto& table, auto&) { table[5].splat_count += 2; });
    EXPECT_NE(error_of([&] { pool::validate_brick_index(counts); }).find("brick 5: size"), std::string::npos);
}

TEST_F(Bricks, BadReferencesAndOldLayoutsAreRefused) {
    const pool::BrickSections s = pool::validate_bricks(*s_bricked);
    const std::uint32_t victim = 2;
    const auto with_ref = [&](std::uint32_t i, std::uint16_t value) {
        return modified(*s_bricked, [&](auto&, auto& table, auto& data) {
            std::byte* base = data.data() + table[victim].offset;
            const pool::BrickHeader& h = *reinterpret_cast<const pool::BrickHeader*>(base);
            std::memcpy(base + pool::brick_refs_offset(h.node_count, h.leaf_count) + 2 * i, &value, 2);
            table[victim].checksum = pool::checksum({base, std::size_t(table[victim].size)});
        });
    };
    const std::uint32_t encoded = s.table[victim].encoded_count;
    ASSERT_LT(encoded, 65535u);
    const std::string outside = error_of([&] { pool::validate_bricks(with_ref(7, std::uint16_t(encoded))); });
    EXPECT_NE(outside.find("brick 2: reference 7 names splat " + std::to_string(encoded)), std::string::npos)
        << outside;
    // pointing every reference of the brick at splat 0 leaves the others unreferenced
    const PoolFile orphans = modified(*s_bricked, [&](auto&, auto& table, auto& data) {
        std::byte* base = data.data() + table[victim].offset;
        const pool::BrickHeader& h = *reinterpret_cast<const pool::BrickHeader*>(base);
        std::memset(base + pool::brick_refs_offset(h.node_count, h.leaf_count), 0, 2 * h.splat_count);
        table[victim].checksum = pool::checksum({base, std::size_t(table[victim].size)});
    });
    EXPECT_NE(
        error_of([&] { pool::validate_bricks(orphans); }).find("brick 2: splat 1 is referenced by no leaf"),
        std::string::npos);
    const PoolFile old =
        modified(*s_bricked, [](auto& info, auto&, auto&) { info.flags &= ~pool::k_bricks_indexed; });
    EXPECT_NE(error_of([&] { pool::validate_brick_index(old); }).find("run prt-bricks again"),
              std::string::npos);
}

/// Brick b's splats in leaf order, decoded (reference i -> its record).
std::vector<pool::DecodedSplat> leaf_order_splats(const pool::BrickSections& s, std::uint32_t b) {
    const pool::BrickView v = pool::brick_view(s.payload(b));
    std::vector<pool::DecodedSplat> out;
    for (std::uint32_t i = 0; i < v.header->splat_count; ++i)
        out.push_back(pool::decode_splat(v.splats[v.ref(i)], *v.header));
    return out;
}

TEST_F(Bricks, DirectBricksHoldTheLeavesSplatsInLeafOrderAndTheSmallerLayoutIsChosen) {
    // The same cut written referenced (never), direct (always) and by size (smaller, the default):
    // every brick's leaves read the same decoded splats in the same order, a direct brick holds
    // one record per reference and no references, and `smaller` picks the smaller payload.
    using D = pre::BrickParams::Direct;
    const PoolFile never =
        PoolFile::from_bytes(test::bricked_bytes(*s_octree, 700, nullptr, true, 32, D::never), "never");
    const PoolFile always =
        PoolFile::from_bytes(test::bricked_bytes(*s_octree, 700, nullptr, true, 32, D::always), "always");
    const pool::BrickSections n = pool::validate_bricks(never);
    const pool::BrickSections a = pool::validate_bricks(always);
    const pool::BrickSections m = pool::validate_bricks(*s_bricked);
    ASSERT_EQ(n.table.size(), a.table.size());
    ASSERT_EQ(m.table.size(), a.table.size());
    EXPECT_EQ(a.info.encoded_splats, a.info.splat_count);
    EXPECT_LT(n.info.encoded_splats, n.info.splat_count);
    std::uint32_t chose_direct = 0;
    for (std::uint32_t b = 0; b < a.table.size(); ++b) {
        SCOPED_TRACE(::testing::Message() << "brick " << b);
        const pool::BrickView va = pool::brick_view(a.payload(b));
        const pool::BrickView vn = pool::brick_view(n.payload(b));
        EXPECT_TRUE(pool::brick_is_direct(*va.header));
        EXPECT_FALSE(pool::brick_is_direct(*vn.header));
        EXPECT_EQ(va.ref_bytes, 0u);
        EXPECT_EQ(a.table[b].encoded_count, a.table[b].splat_count);
        // no references: the records start where the references would
        EXPECT_EQ(reinterpret_cast<const std::byte*>(va.splats.data()) - a.payload(b).data(),
                  std::ptrdiff_t(pool::brick_refs_offset(va.header->node_count, va.header->leaf_count)));
        const auto da = leaf_order_splats(a, b), dn = leaf_order_splats(n, b);
        ASSERT_EQ(da.size(), dn.size());
        for (std::size_t i = 0; i < da.size(); ++i)
            ASSERT_EQ(std::memcmp(&da[i], &dn[i], sizeof(pool::DecodedSplat)), 0) << "reference " << i;
        EXPECT_EQ(std::vector<std::uint32_t>(va.nodes.begin(), va.nodes.end()),
                  std::vector<std::uint32_t>(vn.nodes.begin(), vn.nodes.end()));
        // smaller: the layout of the smaller payload (direct on a tie), with the same splats
        const bool direct = a.table[b].size <= n.table[b].size;
        EXPECT_EQ(m.table[b].size, std::min(a.table[b].size, n.table[b].size));
        EXPECT_EQ(pool::brick_is_direct(*pool::brick_view(m.payload(b)).header), direct);
        chose_direct += direct;
        const auto dm = leaf_order_splats(m, b);
        ASSERT_EQ(dm.size(), dn.size());
        for (std::size_t i = 0; i < dm.size(); ++i)
            ASSERT_EQ(std::memcmp(&dm[i], &dn[i], sizeof(pool::DecodedSplat)), 0) << "reference " << i;
    }
    EXPECT_EQ(chose_direct, s_stats.direct_bricks);
    // An octree without replication (prt-octree --no-replicate, like a culled one with few
    // replicas) stores every brick direct, in fewer bytes than referenced.
    const PoolFile single = PoolFile::from_bytes(octree_pool_bytes(6000, 16, false), "single");
    pre::BrickStats st;
    const PoolFile bricked = PoolFile::from_bytes(test::bricked_bytes(single, 700, &st), "b");
    const pool::BrickSections sb = pool::validate_bricks(bricked);
    EXPECT_EQ(st.direct_bricks, sb.info.brick_count);
    EXPECT_EQ(sb.info.encoded_splats, sb.info.splat_count);
    const PoolFile ref =
        PoolFile::from_bytes(test::bricked_bytes(single, 700, nullptr, true, 32, D::never), "r");
    EXPECT_LT(sb.data.size(), pool::validate_brick_index(ref).data.size());
}

TEST_F(Bricks, DirectBricksWithABadLayoutAreRefused) {
    using D = pre::BrickParams::Direct;
    const PoolFile always =
        PoolFile::from_bytes(test::bricked_bytes(*s_octree, 700, nullptr, true, 32, D::always), "always");
    const auto with_layout = [&](std::uint32_t layout) {
        return modified(always, [&](auto&, auto& table, auto& data) {
            std::byte* base = data.data() + table[2].offset;
            std::memcpy(base + offsetof(pool::BrickHeader, layout), &layout, 4);
            table[2].checksum = pool::checksum({base, std::size_t(table[2].size)});
        });
    };
    EXPECT_NO_THROW(pool::validate_bricks(with_layout(pool::k_brick_direct)));
    // a direct payload whose header says referenced: its size is not the referenced layout's
    EXPECT_NE(error_of([&] {
                  pool::validate_bricks(with_layout(pool::k_brick_referenced));
              }).find("brick 2: payload size"),
              std::string::npos);
    EXPECT_NE(error_of([&] { pool::validate_bricks(with_layout(7)); }).find("brick 2: layout 7"),
              std::string::npos);
    // an entry with fewer records than references cannot be direct: its size matches no layout
    const PoolFile fewer = modified(always, [](auto& info, auto& table, auto&) {
        table[2].encoded_count -= 1;
        info.encoded_splats -= 1;
    });
    EXPECT_NE(error_of([&] { pool::validate_brick_index(fewer); }).find("brick 2: size"), std::string::npos);
}

TEST_F(Bricks, BadBrickNodesAreRefusedNamingTheBrick) {
    // a child address out of the brick's range, checksum made consistent so the structure is checked
    const pool::BrickSections s = pool::validate_bricks(*s_bricked);
    std::uint32_t victim = 0;
    while (victim < s.table.size() && s.table[victim].node_count < 9) ++victim;
    ASSERT_LT(victim, s.table.size());
    const PoolFile bad = modified(*s_bricked, [&](auto&, auto& table, auto& data) {
        std::byte* base = data.data() + table[victim].offset;
        const std::uint32_t word = pool::make_node(NodeType::internal, table[victim].node_count + 5);
        std::memcpy(base + pool::brick_nodes_offset(), &word, 4);
        table[victim].checksum = pool::checksum({base, std::size_t(table[victim].size)});
    });
    EXPECT_NE(error_of([&] {
                  pool::validate_bricks(bad);
              }).find("section brick_data: brick " + std::to_string(victim) + ": node 0:"),
              std::string::npos);
}

TEST_F(Bricks, TopTreeMustAddressEveryBrickOnce) {
    const pool::BrickSections s = pool::validate_bricks(*s_bricked);
    const auto with_top = [&](const std::function<void(std::vector<std::uint32_t>&)>& change) {
        std::vector<std::uint32_t> top(s.top_nodes.begin(), s.top_nodes.end());
        change(top);
        pool::PoolWriter w;
        w.carry_over(*s_bricked);
        w.add_array(SectionType::brick_top_nodes, std::move(top));
        return PoolFile::from_bytes(w.serialize(), "bad.pool");
    };
    const std::uint32_t t1 = s.table[1].top_node;
    // brick 1's node now addresses brick 0 too: brick 0 twice, brick 1 by none
    const PoolFile twice = with_top([&](auto& top) { top[t1] = pool::make_node(NodeType::brick, 0); });
    const std::string e = error_of([&] { pool::validate_brick_index(twice); });
    EXPECT_NE(e.find("section brick_top_nodes: node " + std::to_string(t1) + ": brick 0 addressed twice"),
              std::string::npos)
        << e;
    // a filled leaf in the top tree
    const PoolFile leaf = with_top([&](auto& top) { top[t1] = pool::make_node(NodeType::filled_leaf, 0); });
    EXPECT_NE(error_of([&] { pool::validate_brick_index(leaf); }).find("invalid node type 1"),
              std::string::npos);
    // an entry naming another top node
    const PoolFile swapped = modified(
        *s_bricked, [](auto&, auto& table, auto&) { std::swap(table[0].top_node, table[1].top_node); });
    EXPECT_NE(error_of([&] { pool::validate_brick_index(swapped); }).find("brick 0: top node"),
              std::string::npos);
}

// ---- the tool ------------------------------------------------------------------------------------

class BricksTool : public ::testing::Test {
protected:
    void SetUp() override {
        m_dir = fs::temp_directory_path() / ("prt_bricks_tool_" + std::to_string(::getpid()) + "_" +
                                             ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(m_dir);
        fs::create_directories(m_dir);
    }
    void TearDown() override { fs::remove_all(m_dir); }
    int run(const std::string& args) {
        const test::ToolRun r = test::run_tool("prt-bricks", args, m_dir);
        m_stderr = r.err;
        return r.code;
    }
    std::string path(const std::string& name) const { return (m_dir / name).string(); }
    void write(const std::string& name, const std::vector<std::byte>& bytes) {
        std::ofstream out(path(name), std::ios::binary);
        out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    }
    fs::path m_dir;
    std::string m_stderr;
};

TEST_F(BricksTool, WritesAValidBrickedPool) {
    write("in.pool", octree_pool_bytes(3000));
    ASSERT_EQ(run(path("in.pool") + " -o " + path("out.pool") + " --brick-splats 500 --quiet --stats-json " +
                  path("s.json")),
              0)
        << m_stderr;
    const PoolFile out = PoolFile::open(path("out.pool"));
    const pool::BrickSections b = pool::validate_bricks(out);
    EXPECT_EQ(b.info.brick_splat_limit, 500u);
    EXPECT_FALSE(out.has(SectionType::splats));  // float sections removed by default
    EXPECT_FALSE(out.has(SectionType::octree_nodes));
    // per-point sections removed by default (the bricks carry the colours); the point count stays
    EXPECT_FALSE(out.has(SectionType::colors));
    EXPECT_FALSE(out.has(SectionType::positions));
    EXPECT_EQ(out.model_info().point_count, 3000u);
    EXPECT_TRUE(fs::exists(path("s.json")));
    ASSERT_EQ(run(path("in.pool") + " -o " + path("keep.pool") + " --keep-float --keep-points --quiet"), 0)
        << m_stderr;
    const PoolFile keep = PoolFile::open(path("keep.pool"));
    EXPECT_TRUE(keep.has(SectionType::splats));
    EXPECT_TRUE(keep.has(SectionType::colors));
    EXPECT_TRUE(keep.has(SectionType::positions));
    EXPECT_EQ(pool::validate_bricks(keep).info.flags & pool::k_bricks_float_kept, pool::k_bricks_float_kept);
}

TEST_F(BricksTool, PointsWithoutRadiiGetPrtRadiisRadii) {
    // points with normals and no radii (as prt-import writes them), and the same with prt-radii's
    const test::SplatSet s = test::sphere_points(6000, 7, 2.0);
    pre::PointCloud cloud;
    for (const pool::Float3& p : s.positions) cloud.positions.push_back({p.x, p.y, p.z});
    cloud.normals = s.normals;
    {
        pool::PoolWriter w;
        pre::write_point_sections(cloud, w);
        w.write(path("points.pool"));
    }
    const pre::RadiiParams defaults;  // prt-radii's defaults, over the positions as the pool holds them
    cloud.radii = pre::compute_radii(
        PoolFile::open(path("points.pool")).array<pool::Float3>(SectionType::positions), defaults);
    {
        pool::PoolWriter w;
        pre::write_point_sections(cloud, w);
        w.write(path("radii.pool"));
    }
    const std::string opts = " --brick-splats 2000 --cell-points 2500 --quiet";
    ASSERT_EQ(run(path("radii.pool") + " -o " + path("a.pool") + opts), 0) << m_stderr;
    ASSERT_EQ(run(path("points.pool") + " -o " + path("b.pool") + opts), 0) << m_stderr;
    // --memory below the in-core search: the CPU's out-of-core radii (in a spill file); kept
    ASSERT_EQ(run(path("points.pool") + " -o " + path("c.pool") + opts + " --memory 200K --keep-points"), 0)
        << m_stderr;
    const PoolFile a = PoolFile::open(path("a.pool")), b = PoolFile::open(path("b.pool")),
                   c = PoolFile::open(path("c.pool"));
    for (const SectionType t :
         {SectionType::brick_info, SectionType::brick_top_nodes, SectionType::brick_table,
          SectionType::brick_data, SectionType::brick_lod, SectionType::lod_nodes, SectionType::lod_discs}) {
        ASSERT_TRUE(a.find(t)) << int(t);
        for (const PoolFile* o : {&b, &c}) {
            ASSERT_TRUE(o->find(t)) << int(t);
            EXPECT_EQ(a.find(t)->checksum, o->find(t)->checksum) << "section " << int(t);
        }
    }
    const auto kept = c.array<float>(SectionType::radii);
    ASSERT_EQ(kept.size(), cloud.radii.size());
    EXPECT_EQ(std::memcmp(kept.data(), cloud.radii.data(), kept.size_bytes()), 0);
    EXPECT_NE(c.provenance_json().find("\"radii\":{"), std::string::npos) << c.provenance_json();
    EXPECT_EQ(a.provenance_json().find("\"radii\":{"), std::string::npos);
}

TEST_F(BricksTool, BadInputWritesNothing) {
    // no octree
    pool::PoolWriter w;
    pre::PointCloud cloud;
    cloud.positions = {{0, 0, 0}, {1, 0, 0}};
    pre::write_point_sections(cloud, w);
    w.write(path("points.pool"));
    EXPECT_EQ(run(path("points.pool") + " -o " + path("out.pool")), 1);
    EXPECT_NE(m_stderr.find("no octree"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(path("out.pool")));
    // a corrupted input pool
    std::vector<std::byte> bytes = octree_pool_bytes(500);
    const std::uint64_t splats_at = PoolFile::from_bytes(bytes, "x").find(SectionType::splats)->offset;
    bytes[splats_at + 100] ^= std::byte{1};
    write("bad.pool", bytes);
    EXPECT_EQ(run(path("bad.pool") + " -o " + path("out.pool")), 1);
    EXPECT_NE(m_stderr.find("bad.pool"), std::string::npos) << m_stderr;
    EXPECT_FALSE(fs::exists(path("out.pool")));
    // a usage error
    EXPECT_EQ(run(path("points.pool") + " -o " + path("out.pool") + " --brick-splats 0"), 2);
    EXPECT_FALSE(fs::exists(path("out.pool")));
    // no -o: one line naming the option (only the staged build's plan and cells run without one)
    write("octree.pool", octree_pool_bytes(500));
    EXPECT_EQ(run(path("octree.pool")), 2);
    EXPECT_EQ(m_stderr, "prt-bricks: error: --output is required (see --help)\n");
    EXPECT_EQ(run(path("octree.pool") + " --stage cells --cells 0:1"), 1);  // past -o, to the stage's check
    EXPECT_NE(m_stderr.find("--stage cells needs --cells-folder"), std::string::npos) << m_stderr;
}

}  // namespace

// ---- LOD prefixes (brick_lod, lod_nodes, lod_discs) ------------------------------------------------

/// The pool with its LOD prefix sections changed (`keep`: whether they stay in the pool).
PoolFile modified_lod(
    const PoolFile& good, bool keep,
    const std::function<void(std::vector<pool::BrickLod>&, std::vector<std::uint32_t>&)>& change) {
    const pool::BrickSections s = pool::validate_bricks(good);
    std::vector<pool::BrickLod> table(s.lod_table.begin(), s.lod_table.end());
    std::vector<std::uint32_t> nodes(s.lod_nodes.begin(), s.lod_nodes.end());
    change(table, nodes);
    pool::PoolWriter w;
    w.carry_over(good);
    if (keep) {
        w.add_array(SectionType::brick_lod, std::move(table));
        w.add_array(SectionType::lod_nodes, std::move(nodes));
    } else {
        w.remove(SectionType::lod_nodes);
    }
    return PoolFile::from_bytes(w.serialize(), "bad.pool");
}

TEST_F(Bricks, LodPrefixesAreValidatedNamingTheBrick) {
    const pool::BrickSections good = pool::validate_bricks(*s_bricked);
    ASSERT_EQ(good.lod_table.size(), good.table.size()) << "prt-bricks writes LOD prefixes by default";
    ASSERT_NE(good.info.flags & pool::k_bricks_lod, 0u);
    // one of the three sections missing
    EXPECT_EQ(error_of([&] { pool::validate_bricks(modified_lod(*s_bricked, false, [](auto&, auto&) {})); }),
              "bad.pool: section brick_lod: the LOD prefixes need all of brick_lod, lod_nodes and lod_discs");
    // a prefix longer than its brick
    EXPECT_NE(error_of([&] {
                  pool::validate_bricks(modified_lod(*s_bricked, true, [&](auto& t, auto&) {
                      t[2].node_count = good.table[2].node_count + 1;
                  }));
              }).find("section brick_lod: brick 2: "),
              std::string::npos);
    // a node word that is not the brick's: refused by the index (bad address) or by the brick itself
    const std::uint32_t first = std::uint32_t(good.lod_table[1].first);
    EXPECT_NE(error_of([&] {
                  pool::validate_bricks(modified_lod(*s_bricked, true, [&](auto&, auto& n) {
                      n[first] = pool::make_node(pool::NodeType::internal, 0);  // the root pointing at itself
                  }));
              }).find("section lod_nodes: brick 1: prefix node 0: bad node word"),
              std::string::npos);
    std::uint32_t victim = 0xffffffffu, at = 0;  // a prefix holding an empty leaf: make it look filled
    for (std::uint32_t b = 0; b < good.lod_table.size() && victim == 0xffffffffu; ++b)
        for (std::uint32_t i = 0; i < good.lod_table[b].node_count; ++i)
            if (pool::node_type(good.lod_nodes[good.lod_table[b].first + i]) == pool::NodeType::empty_leaf &&
                good.table[b].leaf_count > 0) {
                victim = b, at = i;
                break;
            }
    ASSERT_NE(victim, 0xffffffffu);
    const PoolFile bad = modified_lod(*s_bricked, true, [&](auto&, auto& n) {
        n[good.lod_table[victim].first + at] = pool::make_node(pool::NodeType::filled_leaf, 0);
    });
    const pool::BrickSections s = pool::validate_brick_index(bad);  // a plausible word: the index passes
    EXPECT_EQ(error_of([&] { pool::validate_brick(bad, s, victim, s.payload(victim)); }),
              "bad.pool: section lod_nodes: brick " + std::to_string(victim) + ": prefix node " +
                  std::to_string(at) + " differs from the brick's node");
}

TEST_F(Bricks, LodPrefixesCanBeLeftOut) {
    const PoolFile none = PoolFile::from_bytes(bricked_bytes(*s_octree, 700, nullptr, true, 0), "none");
    const pool::BrickSections s = pool::validate_bricks(none);
    EXPECT_TRUE(s.lod_table.empty());
    EXPECT_EQ(s.info.flags & pool::k_bricks_lod, 0u);
    EXPECT_FALSE(none.has(SectionType::lod_discs));
}
