#include "prt/runtime/leaf_bounds.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "prt/core/leaf_bounds.h"
#include "prt/parallel.h"

namespace prt::rt {

namespace {

/// Each node's level (the root 0, held at 31 and below) and cell (its integer coordinates at that
/// level), from the root down, and the tree's depth; false when the node pool is not laid out as the
/// walk's index assumes: children blocks of 8 after the root, each behind its parent (so one pass
/// from the last slot back sees children before parents). Pools from prt-octree are laid out so.
struct NodeCells {
    std::vector<std::uint8_t> level;
    std::vector<std::array<std::uint32_t, 3>> cell;
    std::uint32_t depth = 0;
};

bool node_cells(const core::OctreeView& v, NodeCells& out) {
    out.level.assign(v.node_count, 0);
    out.cell.assign(v.node_count, {0u, 0u, 0u});
    out.depth = 0;
    for (std::uint32_t i = 0; i < v.node_count; ++i) {
        const std::uint32_t node = v.nodes[i];
        if (!core::node_is_internal(node)) continue;
        const std::uint32_t addr = core::node_addr(node);
        if (addr <= i || (addr - 1u) % 8u != 0u || addr >= v.node_count || v.node_count - addr < 8u)
            return false;
        for (std::uint32_t c = 0; c < 8; ++c) {
            out.level[addr + c] = static_cast<std::uint8_t>(std::min(out.level[i] + 1, 31));
            for (int a = 0; a < 3; ++a) out.cell[addr + c][a] = 2u * out.cell[i][a] + ((c >> a) & 1u);
        }
        out.depth = std::max<std::uint32_t>(out.depth, out.level[i] + 1u);
    }
    return true;
}

}  // namespace

std::vector<core::LeafBounds> build_leaf_bounds(const core::OctreeView& v, unsigned threads) {
    std::vector<core::LeafBounds> out(v.filled_leaves);
    if (v.filled_leaves == 0 || v.leaf_info == nullptr || v.splats == nullptr) return out;
    parallel_chunks(v.filled_leaves, 4096, resolve_threads(threads),
                    [&](std::size_t first, std::size_t last, unsigned) {
                        for (std::size_t l = first; l < last; ++l) {
                            std::uint32_t b = v.leaf_info[l], e = v.leaf_info[l + 1];
                            e = std::min(e, v.splat_count);  // as core::leaf_splats clamps
                            b = std::min(b, e);
                            out[l] = core::leaf_bounds_of(core::SplatArray{v.splats}, b, e);
                            out[l].begin = b;
                            out[l].end = e;
                        }
                    });
    return out;
}

NodeBoxes build_node_boxes(const core::OctreeView& v, unsigned threads) {
    if (v.node_count == 0 || v.nodes == nullptr || v.leaf_info == nullptr || v.splats == nullptr) return {};
    // Any layout but the walk index's renders without node boxes.
    NodeCells nc;
    if (!node_cells(v, nc)) return {};
    const std::vector<std::uint8_t>& level = nc.level;
    const std::vector<std::array<std::uint32_t, 3>>& cell = nc.cell;
    constexpr float finf = std::numeric_limits<float>::infinity();
    const core::NodeBox empty{{finf, finf, finf}, {-finf, -finf, -finf}};
    const core::NodeBox open{{-finf, -finf, -finf}, {finf, finf, finf}};
    std::vector<core::NodeBox> slot(v.node_count, empty);  // per slot, filled leaves first
    const double root[3] = {v.root_min.x, v.root_min.y, v.root_min.z};
    const double scale = v.inv_root_size;
    parallel_chunks(
        v.node_count, 4096, resolve_threads(threads), [&](std::size_t first, std::size_t last, unsigned) {
            for (std::size_t i = first; i < last; ++i) {
                const std::uint32_t node = v.nodes[i];
                if (!core::node_is_filled(node)) continue;
                const std::uint32_t leaf = core::node_addr(node);
                if (leaf >= v.filled_leaves) {
                    slot[i] = open;
                    continue;
                }
                std::uint32_t b, e;
                core::leaf_splats(v, node, b, e);
                double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
                bool finite = true;
                for (std::uint32_t k = b; k < e && finite; ++k) {
                    const pool::Splat& sp = v.splats[k];
                    const double c[3] = {sp.position.x, sp.position.y, sp.position.z};
                    const double n[3] = {sp.normal.x, sp.normal.y, sp.normal.z};
                    const double r = std::fabs(double(sp.radius));
                    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                    if (!(sp.radius * sp.radius > 0.0f) || !(len > 0))
                        continue;  // intersect_splat never hits it
                    finite = std::isfinite(r) && std::isfinite(len) && std::isfinite(c[0]) &&
                             std::isfinite(c[1]) && std::isfinite(c[2]);
                    // A disk of radius r about unit normal u reaches r sqrt(1 - u_a^2) along axis a.
                    for (int a = 0; a < 3 && finite; ++a) {
                        const double u = n[a] / len;
                        const double h = r * std::sqrt(std::max(0.0, 1.0 - u * u)) * (1.0 + 1e-6);
                        lo[a] = std::min(lo[a], (c[a] - h - root[a]) * scale);
                        hi[a] = std::max(hi[a], (c[a] + h - root[a]) * scale);
                    }
                }
                if (!finite) {
                    slot[i] = open;
                    continue;
                }
                if (!(lo[0] <= hi[0])) continue;  // nothing hittable: empty
                core::NodeBox& o = slot[i];
                for (int a = 0; a < 3; ++a) {  // to float, outward
                    o.lo[a] = std::nextafter(static_cast<float>(lo[a]), -finf);
                    o.hi[a] = std::nextafter(static_cast<float>(hi[a]), finf);
                }
            }
        });
    // Internal nodes from the last slot back: the union of their children's (exact in float).
    NodeBoxes out;
    out.boxes.assign(v.node_count / 8 + 1, empty);
    for (std::uint32_t i = v.node_count; i-- > 0;) {
        const std::uint32_t node = v.nodes[i];
        if (!core::node_is_internal(node)) continue;
        const std::uint32_t addr = core::node_addr(node);
        core::NodeBox u = empty;
        for (std::uint32_t c = 0; c < 8; ++c)
            for (int a = 0; a < 3; ++a) {
                u.lo[a] = std::min(u.lo[a], slot[addr + c].lo[a]);
                u.hi[a] = std::max(u.hi[a], slot[addr + c].hi[a]);
            }
        slot[i] = u;
        out.boxes[(addr - 1u) >> 3] = u;
    }
    // The mask, from the root down (children lie behind their parents): child c of a node is
    // tested when a line through its cell meets its box with a chance under k_node_box_test_below
    // (Cauchy-Crofton: the surface area of the box inside the cell over the cell's).
    out.mask.assign(v.node_count / 8 + 1, 0);
    for (std::uint32_t i = 0; i < v.node_count; ++i) {
        const std::uint32_t node = v.nodes[i];
        if (!core::node_is_internal(node)) continue;
        const std::uint32_t addr = core::node_addr(node);
        std::uint8_t bits = 0;
        for (std::uint32_t c = 0; c < 8; ++c) {
            const std::uint32_t k = addr + c;
            if (!core::node_is_internal(v.nodes[k])) continue;
            const double size = std::ldexp(1.0, -int(level[k]));
            const core::NodeBox& b = slot[k];
            double e[3];
            for (int a = 0; a < 3; ++a) {
                const double lo = cell[k][a] * size, hi = lo + size;
                e[a] = std::max(0.0, std::min(hi, double(b.hi[a])) - std::max(lo, double(b.lo[a])));
            }
            const double area = e[0] * e[1] + e[1] * e[2] + e[0] * e[2];
            if (area < k_node_box_test_below * 3.0 * size * size) bits |= static_cast<std::uint8_t>(1u << c);
        }
        out.mask[(addr - 1u) >> 3] = bits;
    }
    return out;
}

MacroRegions build_macro_regions(const core::OctreeView& v, unsigned threads) {
    if (v.node_count < 9 || v.nodes == nullptr) return {};
    // Trees deeper than the walk resolves would overflow the cells: none.
    NodeCells nc;
    if (!node_cells(v, nc) || nc.depth > core::k_fixed_bits) return {};
    const std::vector<std::uint8_t>& level = nc.level;
    const std::vector<std::array<std::uint32_t, 3>>& cell = nc.cell;
    const std::uint32_t depth = nc.depth;
    // Occupied leaves: a splat tree's where they hold splats; an ISO tree's (no leaf_info:
    // core::IsoView::tree) wherever they are filled, since every filled ISO leaf holds a surface.
    const bool splat_tree = v.leaf_info != nullptr;
    auto occupied = [&](std::uint32_t node) {
        if (!core::node_is_filled(node)) return false;
        if (!splat_tree) return true;
        std::uint32_t b, e;
        core::leaf_splats(v, node, b, e);
        return b < e || core::node_addr(node) >= v.filled_leaves;
    };
    // The grid at level g: 3D prefix sums of the cells an occupied leaf reaches.
    const std::uint32_t g = std::min(depth, k_macro_region_levels);
    const std::size_t n = std::size_t{1} << g, m = n + 1;
    std::vector<std::uint32_t> sum(m * m * m, 0u);
    auto at = [m](std::size_t x, std::size_t y, std::size_t z) { return (x * m + y) * m + z; };
    for (std::uint32_t i = 0; i < v.node_count; ++i) {
        if (!occupied(v.nodes[i])) continue;
        std::size_t lo[3], hi[3];  // grid cells [lo, hi)
        for (int a = 0; a < 3; ++a) {
            if (level[i] <= g) {
                lo[a] = std::size_t{cell[i][a]} << (g - level[i]);
                hi[a] = std::size_t{cell[i][a] + 1u} << (g - level[i]);
            } else {
                lo[a] = cell[i][a] >> (level[i] - g);
                hi[a] = lo[a] + 1;
            }
        }
        for (std::size_t x = lo[0]; x < hi[0]; ++x)
            for (std::size_t y = lo[1]; y < hi[1]; ++y)
                for (std::size_t z = lo[2]; z < hi[2]; ++z) sum[at(x + 1, y + 1, z + 1)] = 1u;
    }
    // Prefix sums axis by axis (z, then y, then x), each pass's rows in parallel.
    const unsigned workers = resolve_threads(threads);
    parallel_chunks(m - 1, 1, workers, [&](std::size_t first, std::size_t last, unsigned) {
        for (std::size_t x = first + 1; x <= last; ++x) {
            for (std::size_t y = 1; y < m; ++y)
                for (std::size_t z = 1; z < m; ++z) sum[at(x, y, z)] += sum[at(x, y, z - 1)];
            for (std::size_t y = 1; y < m; ++y)
                for (std::size_t z = 1; z < m; ++z) sum[at(x, y, z)] += sum[at(x, y - 1, z)];
        }
    });
    parallel_chunks(m - 1, 1, workers, [&](std::size_t first, std::size_t last, unsigned) {
        for (std::size_t y = first + 1; y <= last; ++y)
            for (std::size_t x = 1; x < m; ++x)
                for (std::size_t z = 1; z < m; ++z) sum[at(x, y, z)] += sum[at(x - 1, y, z)];
    });
    // Whether cells [lo, hi] (inclusive) at level l <= g hold no splat.
    auto free_box = [&](std::uint32_t l, const std::uint32_t lo[3], const std::uint32_t hi[3]) {
        const std::uint32_t k = g - l;
        const std::size_t x0 = std::size_t{lo[0]} << k, y0 = std::size_t{lo[1]} << k,
                          z0 = std::size_t{lo[2]} << k;
        const std::size_t x1 = std::size_t{hi[0] + 1u} << k, y1 = std::size_t{hi[1] + 1u} << k,
                          z1 = std::size_t{hi[2] + 1u} << k;
        const std::uint32_t s = sum[at(x1, y1, z1)] - sum[at(x0, y1, z1)] - sum[at(x1, y0, z1)] -
                                sum[at(x1, y1, z0)] + sum[at(x0, y0, z1)] + sum[at(x0, y1, z0)] +
                                sum[at(x1, y0, z0)] - sum[at(x0, y0, z0)];
        return s == 0u;
    };
    // The box of free cells around empty leaf i's cell, at its level: the directions of axis
    // `first_axis` grown as far as they go first, then all six in turn (x-, x+, y-, y+, z-, z+),
    // each by doubling steps while the box stays free and, once a step fails, by halving ones (a
    // binary search for the last free slab), up to 255 cells each way and inside the root.
    auto grow = [&](std::size_t i, int first_axis) {
        const std::uint32_t l = level[i];
        const std::uint32_t top = (1u << l) - 1u;
        std::uint32_t lo[3] = {cell[i][0], cell[i][1], cell[i][2]}, hi[3] = {lo[0], lo[1], lo[2]};
        std::uint32_t step[6] = {1, 1, 1, 1, 1, 1};
        bool open[6] = {true, true, true, true, true, true};
        bool refining[6] = {false, false, false, false, false, false};
        for (int phase = 0; phase < 2; ++phase) {
            for (bool grew = true; grew;) {  // bounded: each pass grows a box or halves a step
                grew = false;
                for (int dir = 0; dir < 6; ++dir) {
                    const int a = dir / 2;
                    if (!open[dir] || (phase == 0 && a != first_axis)) continue;
                    const bool up = (dir & 1) != 0;
                    const std::uint32_t c = cell[i][a];
                    const std::uint32_t room =
                        up ? std::min(top - hi[a], 255u - (hi[a] - c)) : std::min(lo[a], 255u - (c - lo[a]));
                    const std::uint32_t k = std::min(step[dir], room);
                    if (k == 0) {
                        open[dir] = false;
                        continue;
                    }
                    std::uint32_t slo[3] = {lo[0], lo[1], lo[2]}, shi[3] = {hi[0], hi[1], hi[2]};
                    if (up) {
                        slo[a] = hi[a] + 1u;
                        shi[a] = hi[a] + k;
                    } else {
                        slo[a] = lo[a] - k;
                        shi[a] = lo[a] - 1u;
                    }
                    if (free_box(l, slo, shi)) {
                        (up ? hi[a] : lo[a]) = up ? shi[a] : slo[a];
                        step[dir] = refining[dir] ? k / 2u : 2u * k;
                        grew = true;
                    } else if (k > 1u) {
                        step[dir] = k / 2u;
                        refining[dir] = true;
                        grew = true;
                    } else {
                        open[dir] = false;
                    }
                }
            }
        }
        core::MacroRegion r{};
        for (int a = 0; a < 3; ++a) {
            r.below[a] = static_cast<std::uint8_t>(cell[i][a] - lo[a]);
            r.above[a] = static_cast<std::uint8_t>(hi[a] - cell[i][a]);
        }
        return r;
    };
    // The empty leaves that may get regions, then their three boxes (core::k_region_axes) in parallel.
    std::vector<std::uint32_t> empty;
    for (std::uint32_t i = 0; i < v.node_count; ++i)
        if (!core::node_is_internal(v.nodes[i]) && !occupied(v.nodes[i]) && level[i] != 0 && level[i] <= g)
            empty.push_back(i);
    std::vector<core::MacroRegion> region(empty.size() * core::k_region_axes, core::MacroRegion{});
    parallel_chunks(empty.size(), 1024, workers, [&](std::size_t first, std::size_t last, unsigned) {
        for (std::size_t e = first; e < last; ++e)
            for (std::uint32_t a = 0; a < core::k_region_axes; ++a)
                region[e * core::k_region_axes + a] = grow(empty[e], static_cast<int>(a));
    });
    MacroRegions out;
    out.nodes.assign(v.nodes, v.nodes + v.node_count);
    for (std::uint32_t i = 0; i < v.node_count; ++i)
        // An empty leaf's address is 0 in a valid pool (walk_step reads a region for any other):
        // kept so for those without a region whatever the words said.
        if ((v.nodes[i] & ~pool::k_node_address_max) == core::k_empty_leaf_node)
            out.nodes[i] = core::k_empty_leaf_node;
    out.regions.assign(core::k_region_axes, core::MacroRegion{});
    for (std::size_t e = 0; e < empty.size(); ++e) {
        const core::MacroRegion* r = &region[e * core::k_region_axes];
        bool grown = false;
        for (std::uint32_t a = 0; a < core::k_region_axes; ++a)
            grown = grown || (r[a].below[0] | r[a].below[1] | r[a].below[2] | r[a].above[0] | r[a].above[1] |
                              r[a].above[2]) != 0;
        if (!grown) continue;
        const std::size_t address = out.regions.size() / core::k_region_axes;
        if (address > pool::k_node_address_max) break;  // no address left: the rest go without
        out.nodes[empty[e]] =
            pool::make_node(pool::NodeType::empty_leaf, static_cast<std::uint32_t>(address));
        out.regions.insert(out.regions.end(), r, r + core::k_region_axes);
    }
    return out;
}

namespace {

/// The compact leaf bounds of a brick opened by core::open_brick, over its splats decoded once.
std::vector<core::BrickLeafBounds> opened_brick_bounds(const core::BrickSplats& src,
                                                       const core::OctreeView& brick,
                                                       std::vector<pool::Splat>& decoded) {
    decoded.resize(brick.splat_count);
    for (std::uint32_t i = 0; i < brick.splat_count; ++i) decoded[i] = src.load(i);
    std::vector<core::BrickLeafBounds> out(brick.filled_leaves);
    for (std::uint32_t l = 0; l < brick.filled_leaves; ++l) {
        std::uint32_t e = std::min(brick.leaf_info[l + 1], brick.splat_count);
        std::uint32_t b = std::min(brick.leaf_info[l], e);
        out[l] = core::brick_leaf_bounds_of(core::SplatArray{decoded.data()}, b, e);
    }
    return out;
}

}  // namespace

std::vector<core::BrickLeafBounds> build_brick_leaf_bounds(const core::BrickView& v,
                                                           std::vector<std::uint32_t>& first,
                                                           unsigned threads) {
    first.assign(std::size_t{v.brick_count} + 1, 0);
    for (std::uint32_t b = 0; b < v.brick_count; ++b) first[b + 1] = first[b] + v.table[b].leaf_count;
    std::vector<core::BrickLeafBounds> out(first.back());
    parallel_chunks(
        v.brick_count, 1, resolve_threads(threads), [&](std::size_t b0, std::size_t b1, unsigned) {
            std::vector<pool::Splat> decoded;
            for (std::size_t b = b0; b < b1; ++b) {
                core::BrickSplats src;
                core::OctreeView brick;
                if (!core::open_brick(v, static_cast<std::uint32_t>(b), src, brick)) continue;
                const std::vector<core::BrickLeafBounds> leaves = opened_brick_bounds(src, brick, decoded);
                std::copy(leaves.begin(), leaves.end(), out.begin() + first[b]);
            }
        });
    return out;
}

std::vector<core::BrickLeafBounds> build_one_brick_leaf_bounds(const pool::BrickEntry& entry,
                                                               const unsigned char* payload) {
    const unsigned char* resident[1] = {payload};
    core::BrickView v;
    v.table = &entry;
    v.brick_count = 1;
    v.resident = resident;
    core::BrickSplats src;
    core::OctreeView brick;
    std::vector<pool::Splat> decoded;
    if (!core::open_brick(v, 0, src, brick)) return {};
    return opened_brick_bounds(src, brick, decoded);
}

}  // namespace prt::rt
