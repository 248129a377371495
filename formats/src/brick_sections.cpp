// PointRT pool file: validation of the brick sections (brick_sections.h; rules in formats/POOL.md,
// "Bricks and level of detail"): a bad pool is a one-line error naming the brick, never a crash.
#include "prt/formats/brick_sections.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include "section_checks.h"

namespace prt::pool {

namespace {

constexpr SectionType k_brick_types[] = {SectionType::brick_info, SectionType::brick_top_nodes,
                                         SectionType::brick_table, SectionType::brick_data,
                                         SectionType::lod_splats};

std::string brick_label(std::uint32_t b) {
    return "brick " + std::to_string(b) + ": ";
}

/// The top tree: a proper tree from node 0 with internal, empty and brick nodes only, each brick
/// addressed once (check_node_tree with bricks as its leaves) by the node its entry names, at that
/// node's level and cube.
void check_top_tree(const PoolFile& pool, const BrickSections& s) {
    const SectionEntry* et = pool.find(SectionType::brick_table);
    detail::check_node_tree(pool, pool.find(SectionType::brick_top_nodes), s.top_nodes,
                            static_cast<std::uint32_t>(s.table.size()),
                            std::min<std::uint32_t>(s.info.depth, 30), false, "", NodeType::brick);
    // the tree is proper: levels and cells in one pass, children after their parent
    const std::size_t count = s.top_nodes.size();
    std::vector<std::uint32_t> level(count, 0), cell(3 * count, 0);
    for (std::uint32_t i = 0; i < count; ++i) {
        const std::uint32_t a = node_address(s.top_nodes[i]);
        if (node_type(s.top_nodes[i]) == NodeType::internal) {
            for (std::uint32_t c = 0; c < 8; ++c) {
                level[a + c] = level[i] + 1;
                for (int ax = 0; ax < 3; ++ax)
                    cell[3 * (a + c) + ax] = 2 * cell[3 * i + ax] + ((c >> ax) & 1);
            }
            continue;
        }
        if (node_type(s.top_nodes[i]) != NodeType::brick) continue;
        const BrickEntry& e = s.table[a];
        if (e.top_node != i)
            pool.fail(et, brick_label(a) + "top node " + std::to_string(e.top_node) + " but node " +
                              std::to_string(i) + " addresses it");
        if (e.level != level[i])
            pool.fail(et, brick_label(a) + "level " + std::to_string(e.level) + " but its node is at level " +
                              std::to_string(level[i]));
        const double size = double(s.info.root_size) / double(std::uint64_t(1) << level[i]);
        const double tol = 1e-5 * size;
        bool cube_ok = std::fabs(double(e.cube_size) - size) <= tol;
        for (int ax = 0; ax < 3; ++ax) {
            const double want = double(s.info.root_min[ax]) + size * cell[3 * i + ax];
            cube_ok = cube_ok && std::fabs(double(e.cube_min[ax]) - want) <= tol + 1e-6 * std::fabs(want);
        }
        if (!cube_ok) pool.fail(et, brick_label(a) + "cube is not its top node's cube");
    }
}

/// Payload ranges aligned, inside brick_data, of their counts' size, not overlapping; counts adding up.
void check_table(const PoolFile& pool, const BrickSections& s) {
    const SectionEntry* et = pool.find(SectionType::brick_table);
    const SectionEntry* ei = pool.find(SectionType::brick_info);
    const std::uint64_t data_size = s.data.size();
    std::uint64_t splats = 0, encoded = 0;
    std::uint32_t max_splats = 0;
    for (std::uint32_t b = 0; b < s.table.size(); ++b) {
        const BrickEntry& e = s.table[b];
        if (e.offset % k_brick_alignment != 0)
            pool.fail(et, brick_label(b) + "offset " + std::to_string(e.offset) + " not a multiple of 64");
        if (e.offset > data_size || e.size > data_size - e.offset)
            pool.fail(et, brick_label(b) + "payload [" + std::to_string(e.offset) + ", +" +
                              std::to_string(e.size) + ") outside brick_data (" + std::to_string(data_size) +
                              " bytes)");
        if (e.node_count == 0) pool.fail(et, brick_label(b) + "no nodes (the root is missing)");
        if (e.encoded_count > e.splat_count || (e.encoded_count == 0) != (e.splat_count == 0))
            pool.fail(et, brick_label(b) + std::to_string(e.encoded_count) + " encoded splats for " +
                              std::to_string(e.splat_count) + " references");
        const std::uint64_t want = brick_payload_size(e.node_count, e.leaf_count, e.splat_count,
                                                      e.encoded_count, brick_entry_is_direct(e));
        if (e.size != want)
            pool.fail(et, brick_label(b) + "size " + std::to_string(e.size) + " does not match its counts (" +
                              std::to_string(want) + " bytes)");
        splats += e.splat_count;
        encoded += e.encoded_count;
        max_splats = std::max(max_splats, e.splat_count);
    }
    std::vector<std::uint32_t> order(s.table.size());
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(),
              [&](std::uint32_t a, std::uint32_t b) { return s.table[a].offset < s.table[b].offset; });
    for (std::size_t k = 1; k < order.size(); ++k) {
        const BrickEntry& prev = s.table[order[k - 1]];
        if (prev.offset + prev.size > s.table[order[k]].offset)
            pool.fail(
                et, brick_label(order[k]) + "payload overlaps brick " + std::to_string(order[k - 1]) + "'s");
    }
    if (splats != s.info.splat_count)
        pool.fail(ei, "bricks hold " + std::to_string(splats) + " splats but brick_info says " +
                          std::to_string(s.info.splat_count));
    if (encoded != s.info.encoded_splats)
        pool.fail(ei, "bricks hold " + std::to_string(encoded) + " encoded splats but brick_info says " +
                          std::to_string(s.info.encoded_splats));
    if (max_splats != s.info.max_brick_splats)
        pool.fail(ei, "largest brick holds " + std::to_string(max_splats) + " splats but brick_info says " +
                          std::to_string(s.info.max_brick_splats));
}

bool finite3(const Float3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// The optional LOD prefixes (brick_lod, lod_nodes, lod_discs): present together as the flag says,
/// one per brick inside lod_nodes, each a proper prefix of its brick's breadth-first node array.
void check_lod_prefixes(const PoolFile& pool, BrickSections& s) {
    const SectionEntry* eb = pool.find(SectionType::brick_lod);
    const SectionEntry* en = pool.find(SectionType::lod_nodes);
    const SectionEntry* ed = pool.find(SectionType::lod_discs);
    const bool flagged = (s.info.flags & k_bricks_lod) != 0;
    if (eb == nullptr && en == nullptr && ed == nullptr) {
        if (flagged)
            pool.fail(pool.find(SectionType::brick_info),
                      "says LOD prefixes but brick_lod, lod_nodes and lod_discs are missing");
        return;
    }
    if (eb == nullptr || en == nullptr || ed == nullptr)
        pool.fail(eb ? eb : (en ? en : ed),
                  "the LOD prefixes need all of brick_lod, lod_nodes and lod_discs");
    if (!flagged) pool.fail(eb, "present but brick_info's flags do not say LOD prefixes");
    s.lod_table = pool.array<BrickLod>(SectionType::brick_lod);
    s.lod_nodes = pool.array<std::uint32_t>(SectionType::lod_nodes);
    s.lod_discs = pool.array<CompressedSplat>(SectionType::lod_discs);
    detail::check_count(pool, eb, s.lod_table.size(), s.info.brick_count, "prefixes", "brick_info");
    detail::check_count(pool, ed, s.lod_discs.size(), s.lod_nodes.size(), "discs", "lod_nodes");
    if (s.lod_nodes.size() > 0xFFFFFFFFull) pool.fail(en, "more than 2^32 - 1 nodes");
    for (std::uint32_t b = 0; b < s.lod_table.size(); ++b) {
        const BrickLod& l = s.lod_table[b];
        const BrickEntry& e = s.table[b];
        const auto fail = [&](const SectionEntry* where, const std::string& what) {
            pool.fail(where, brick_label(b) + what);
        };
        if (l.node_count == 0 || l.node_count > e.node_count)
            fail(eb, std::to_string(l.node_count) + " prefix nodes, the brick has " +
                         std::to_string(e.node_count));
        if (l.first > s.lod_nodes.size() || l.node_count > s.lod_nodes.size() - l.first)
            fail(eb, "prefix [" + std::to_string(l.first) + ", +" + std::to_string(l.node_count) +
                         ") outside lod_nodes (" + std::to_string(s.lod_nodes.size()) + ")");
        if (!(l.quant_size > 0) || !std::isfinite(l.quant_size) || !std::isfinite(l.quant_min[0]) ||
            !std::isfinite(l.quant_min[1]) || !std::isfinite(l.quant_min[2]))
            fail(eb, "quantization cube not finite with a positive size");
        if (l.radius_log2_min < -k_radius_log2_limit || l.radius_log2_min > k_radius_log2_limit - 32)
            fail(eb, "radius exponent " + std::to_string(l.radius_log2_min) + " out of range");
        for (std::uint32_t i = 0; i < l.node_count; ++i) {
            const std::uint32_t w = s.lod_nodes[l.first + i];
            const std::uint32_t a = node_address(w);
            bool ok = true;
            switch (node_type(w)) {
                case NodeType::internal:
                    ok = a > i && std::uint64_t(a) + 8 <= e.node_count;
                    break;
                case NodeType::filled_leaf:
                    ok = a < e.leaf_count;
                    break;
                case NodeType::empty_leaf:
                    break;
                default:
                    ok = false;
                    break;
            }
            if (!ok) fail(en, "prefix node " + std::to_string(i) + ": bad node word");
            const std::uint32_t nr = s.lod_discs[l.first + i].nr;
            if ((nr & 1023u) > k_oct_max_code || ((nr >> 10) & 1023u) > k_oct_max_code)
                fail(ed, "prefix node " + std::to_string(i) + ": normal code out of range");
        }
    }
}

}  // namespace

BrickView brick_view(std::span<const std::byte> payload) {
    BrickView v;
    v.header = reinterpret_cast<const BrickHeader*>(payload.data());
    const BrickHeader& h = *v.header;
    v.nodes = {reinterpret_cast<const std::uint32_t*>(payload.data() + brick_nodes_offset()), h.node_count};
    v.leaf_info = {
        reinterpret_cast<const std::uint32_t*>(payload.data() + brick_leaf_info_offset(h.node_count)),
        std::size_t(h.leaf_count) + 1};
    const bool direct = brick_is_direct(h);
    v.refs = direct ? nullptr : payload.data() + brick_refs_offset(h.node_count, h.leaf_count);
    v.ref_bytes = direct ? 0 : brick_ref_bytes(h.encoded_count);
    v.splats = {reinterpret_cast<const CompressedSplat*>(
                    payload.data() +
                    brick_splats_offset(h.node_count, h.leaf_count, h.splat_count, h.encoded_count, direct)),
                h.encoded_count};
    return v;
}

bool has_bricks(const PoolFile& pool) {
    return detail::first_present(pool, k_brick_types) != nullptr;
}

BrickSections validate_brick_index(const PoolFile& pool) {
    detail::require_sections(pool, k_brick_types, std::size(k_brick_types),
                             "the bricks need all of brick_info, brick_top_nodes, brick_table, brick_data, "
                             "lod_splats",
                             "brick");
    BrickSections s;
    s.info = detail::single<BrickInfo>(pool, SectionType::brick_info);
    s.top_nodes = pool.array<std::uint32_t>(SectionType::brick_top_nodes);
    s.table = pool.array<BrickEntry>(SectionType::brick_table);
    s.data = pool.array<std::byte>(SectionType::brick_data);
    s.lod = pool.array<LodSplat>(SectionType::lod_splats);
    const SectionEntry* ei = pool.find(SectionType::brick_info);
    detail::check_count(pool, pool.find(SectionType::brick_table), s.table.size(), s.info.brick_count,
                        "bricks", "brick_info");
    detail::check_count(pool, pool.find(SectionType::brick_top_nodes), s.top_nodes.size(),
                        s.info.top_node_count, "nodes", "brick_info");
    detail::check_count(pool, pool.find(SectionType::lod_splats), s.lod.size(), s.info.top_node_count,
                        "discs", "brick_info top_node_count");
    if (s.top_nodes.empty())
        pool.fail(pool.find(SectionType::brick_top_nodes), "no nodes (the root is missing)");
    if ((s.info.flags & k_bricks_indexed) == 0)
        pool.fail(ei,
                  "bricks of an older prt-bricks (a splat copied into every leaf, no splat index): "
                  "run prt-bricks again");
    if (!(s.info.root_size > 0) || !std::isfinite(s.info.root_size) || !std::isfinite(s.info.root_min[0]) ||
        !std::isfinite(s.info.root_min[1]) || !std::isfinite(s.info.root_min[2]))
        pool.fail(ei, "root cube not finite with a positive size");
    if (s.info.depth > 255) pool.fail(ei, "depth " + std::to_string(s.info.depth) + " exceeds 255");
    check_table(pool, s);
    check_top_tree(pool, s);
    const SectionEntry* el = pool.find(SectionType::lod_splats);
    for (std::size_t i = 0; i < s.lod.size(); ++i) {
        const LodSplat& d = s.lod[i];
        if (!finite3(d.position) || !finite3(d.normal) || !std::isfinite(d.radius) || d.radius < 0)
            pool.fail(el, "disc " + std::to_string(i) + ": not finite or a negative radius");
    }
    check_lod_prefixes(pool, s);
    return s;
}

void validate_brick(const PoolFile& pool, const BrickSections& sections, std::uint32_t index,
                    std::span<const std::byte> payload) {
    const BrickInfo& info = sections.info;
    const BrickEntry& entry = sections.table[index];
    const SectionEntry* ed = pool.find(SectionType::brick_data);
    const std::string where = brick_label(index);
    const auto fail = [&](const std::string& what) { pool.fail(ed, where + what); };
    if (payload.size() != entry.size)
        fail(std::to_string(payload.size()) + " bytes but its entry says " + std::to_string(entry.size));
    if (payload.size() < sizeof(BrickHeader) || entry.node_count == 0 ||
        entry.encoded_count > entry.splat_count)
        fail("payload size " + std::to_string(payload.size()) + " does not match its entry's counts");
    if (checksum(payload) != entry.checksum) fail("checksum mismatch");
    const BrickHeader& hdr = *reinterpret_cast<const BrickHeader*>(payload.data());
    if (hdr.layout != k_brick_referenced && hdr.layout != k_brick_direct)
        fail("layout " + std::to_string(hdr.layout) + " is neither referenced (0) nor direct (1)");
    const bool direct = brick_is_direct(hdr);
    if (direct && entry.encoded_count != entry.splat_count)
        fail("direct, but " + std::to_string(entry.encoded_count) + " encoded splats for " +
             std::to_string(entry.splat_count) + " references");
    if (payload.size() != brick_payload_size(entry.node_count, entry.leaf_count, entry.splat_count,
                                             entry.encoded_count, direct))
        fail("payload size " + std::to_string(payload.size()) + " does not match its entry's counts (" +
             (direct ? "direct" : "referenced") + ")");
    const BrickView v = brick_view(payload);
    const BrickHeader& h = *v.header;
    if (h.node_count != entry.node_count || h.leaf_count != entry.leaf_count ||
        h.splat_count != entry.splat_count || h.encoded_count != entry.encoded_count)
        fail("header counts differ from its entry's");
    if (!(h.quant_size > 0) || !std::isfinite(h.quant_size) || !std::isfinite(h.quant_min[0]) ||
        !std::isfinite(h.quant_min[1]) || !std::isfinite(h.quant_min[2]))
        fail("quantization cube not finite with a positive size");
    if (h.radius_log2_min < -k_radius_log2_limit || h.radius_log2_min > k_radius_log2_limit - 32)
        fail("radius exponent " + std::to_string(h.radius_log2_min) + " out of range");
    if (entry.level > info.depth)
        fail("level " + std::to_string(entry.level) + " below the tree's depth " +
             std::to_string(info.depth));
    detail::check_node_tree(pool, ed, v.nodes, h.leaf_count, info.depth - entry.level, false, where);
    for (std::size_t i = 0; i + 1 < v.leaf_info.size(); ++i)
        if (v.leaf_info[i] > v.leaf_info[i + 1]) fail("leaf " + std::to_string(i) + ": begin after end");
    if (v.leaf_info.front() != 0 || v.leaf_info.back() != h.splat_count)
        fail("leaf ranges do not cover the references exactly");
    std::vector<bool> referenced(h.encoded_count, false);
    for (std::size_t i = 0; i < h.splat_count; ++i) {
        const std::uint32_t k = v.ref(i);
        if (k >= h.encoded_count)
            fail("reference " + std::to_string(i) + " names splat " + std::to_string(k) + " of " +
                 std::to_string(h.encoded_count));
        referenced[k] = true;
    }
    if (const auto it = std::find(referenced.begin(), referenced.end(), false); it != referenced.end())
        fail("splat " + std::to_string(it - referenced.begin()) + " is referenced by no leaf");
    for (std::size_t i = 0; i < v.splats.size(); ++i) {
        const std::uint32_t nr = v.splats[i].nr;
        if ((nr & 1023u) > k_oct_max_code || ((nr >> 10) & 1023u) > k_oct_max_code)
            fail("splat " + std::to_string(i) + ": normal code out of range");
    }
    const std::span<const std::uint32_t> prefix = sections.lod_prefix(index);
    for (std::size_t i = 0; i < prefix.size(); ++i)
        if (prefix[i] != v.nodes[i])
            pool.fail(pool.find(SectionType::lod_nodes),
                      where + "prefix node " + std::to_string(i) + " differs from the brick's node");
    if (!prefix.empty()) {
        const BrickLod& l = sections.lod_table[index];
        if (l.quant_size != h.quant_size || l.quant_min[0] != h.quant_min[0] ||
            l.quant_min[1] != h.quant_min[1] || l.quant_min[2] != h.quant_min[2])
            pool.fail(pool.find(SectionType::brick_lod),
                      where + "quantization cube differs from the brick's");
    }
}

BrickSections validate_bricks(const PoolFile& pool) {
    BrickSections s = validate_brick_index(pool);
    for (std::uint32_t b = 0; b < s.table.size(); ++b) validate_brick(pool, s, b, s.payload(b));
    return s;
}

}  // namespace prt::pool
