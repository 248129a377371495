// Test-only helpers for the runtime tests: analytic point sets, a tiny brute-force octree builder
// written independently of prt-octree (recursive, host only), and in-memory pools.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "prt/core/octree.h"
#include "prt/formats/pool.h"

namespace prt::test {

using D3 = std::array<double, 3>;

inline D3 d3_add(const D3& a, const D3& b) {
    return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}
inline D3 d3_sub(const D3& a, const D3& b) {
    return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
inline D3 d3_mul(const D3& a, double s) {
    return {a[0] * s, a[1] * s, a[2] * s};
}
inline double d3_dot(const D3& a, const D3& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline double d3_len(const D3& a) {
    return std::sqrt(d3_dot(a, a));
}
inline D3 d3_norm(const D3& a) {
    return d3_mul(a, 1.0 / d3_len(a));
}

/// A point with a normal, a splat radius and a color, in world coordinates (double).
struct TestPoint {
    D3 position;
    D3 normal;
    double radius;
    pool::Rgba8 color{200, 200, 200, 255};
};

/// Radius that covers a uniformly sampled surface of area `area` with `n` points: the distance to
/// about the k-th neighbour, sqrt(k A / (pi n)) (thesis 3.1 for uniform density).
inline double density_radius(double area, std::size_t n, double k = 9.0) {
    return std::sqrt(k * area / (3.14159265358979323846 * static_cast<double>(n)));
}

/// Fibonacci-sphere samples of a sphere (outward normals, or inward when `inward`).
inline std::vector<TestPoint> sphere_points(const D3& center, double radius, std::size_t n,
                                            bool inward = false, pool::Rgba8 color = {200, 200, 200, 255}) {
    std::vector<TestPoint> pts;
    const double golden = 3.14159265358979323846 * (3.0 - std::sqrt(5.0));
    const double r = density_radius(4.0 * 3.14159265358979323846 * radius * radius, n);
    for (std::size_t i = 0; i < n; ++i) {
        const double y = 1.0 - 2.0 * (static_cast<double>(i) + 0.5) / static_cast<double>(n);
        const double rho = std::sqrt(std::max(0.0, 1.0 - y * y));
        const double phi = golden * static_cast<double>(i);
        const D3 nrm{rho * std::cos(phi), y, rho * std::sin(phi)};
        pts.push_back({d3_add(center, d3_mul(nrm, radius)), inward ? d3_mul(nrm, -1.0) : nrm, r, color});
    }
    return pts;
}

/// A square grid of points on the rectangle origin + s u + t v (s, t in [0, 1]) with normal `n`,
/// `per_side` x `per_side` points; radius 1.2 x the grid cell diagonal, so the disks leave no holes.
inline std::vector<TestPoint> rect_points(const D3& origin, const D3& u, const D3& v, const D3& n,
                                          std::size_t per_side, pool::Rgba8 color = {200, 200, 200, 255}) {
    std::vector<TestPoint> pts;
    const double du = d3_len(u) / static_cast<double>(per_side),
                 dv = d3_len(v) / static_cast<double>(per_side);
    const double r = 1.2 * std::sqrt(du * du + dv * dv);  // more than half a cell diagonal: no holes
    for (std::size_t i = 0; i < per_side; ++i) {
        for (std::size_t j = 0; j < per_side; ++j) {
            const double s = (static_cast<double>(i) + 0.5) / static_cast<double>(per_side);
            const double t = (static_cast<double>(j) + 0.5) / static_cast<double>(per_side);
            pts.push_back({d3_add(origin, d3_add(d3_mul(u, s), d3_mul(v, t))), d3_norm(n), r, color});
        }
    }
    return pts;
}

/// The inside of the box [lo, hi]^3 (normals pointing into the room), `per_side` points per wall
/// side; `skip_wall` (0..5: -x, +x, -y, +y, -z, +z) leaves one wall out (-1: closed room).
inline std::vector<TestPoint> room_points(double lo, double hi, std::size_t per_side, int skip_wall = -1,
                                          pool::Rgba8 color = {200, 200, 200, 255}) {
    std::vector<TestPoint> all;
    const double s = hi - lo;
    auto add = [&](int wall, const std::vector<TestPoint>& p) {
        if (wall != skip_wall) all.insert(all.end(), p.begin(), p.end());
    };
    add(0, rect_points({lo, lo, lo}, {0, s, 0}, {0, 0, s}, {1, 0, 0}, per_side, color));
    add(1, rect_points({hi, lo, lo}, {0, s, 0}, {0, 0, s}, {-1, 0, 0}, per_side, color));
    add(2, rect_points({lo, lo, lo}, {s, 0, 0}, {0, 0, s}, {0, 1, 0}, per_side, color));
    add(3, rect_points({lo, hi, lo}, {s, 0, 0}, {0, 0, s}, {0, -1, 0}, per_side, color));
    add(4, rect_points({lo, lo, lo}, {s, 0, 0}, {0, s, 0}, {0, 0, 1}, per_side, color));
    add(5, rect_points({lo, lo, hi}, {s, 0, 0}, {0, s, 0}, {0, 0, -1}, per_side, color));
    return all;
}

/// One leaf of a test octree, for reference checks.
struct TestLeaf {
    std::uint32_t node_index;
    std::uint32_t level;
    std::uint64_t cell[3];
    bool filled;
};

/// A built octree (pool section contents) plus its leaves.
struct TestOctree {
    pool::OctreeInfo info{};
    std::vector<std::uint32_t> nodes;
    std::vector<std::uint32_t> leaf_info;
    std::vector<pool::Splat> splats;
    std::vector<TestLeaf> leaves;

    core::OctreeView view() const {
        core::OctreeView v;
        v.nodes = nodes.data();
        v.node_count = static_cast<std::uint32_t>(nodes.size());
        v.leaf_info = leaf_info.data();
        v.filled_leaves = static_cast<std::uint32_t>(leaf_info.size() - 1);
        v.splats = splats.data();
        v.splat_count = static_cast<std::uint32_t>(splats.size());
        v.root_min = {info.root_min[0], info.root_min[1], info.root_min[2]};
        v.root_size = info.root_size;
        v.inv_root_size = 1.0f / info.root_size;
        v.flags = info.flags;
        return v;
    }
};

/// Brute-force octree over splats (local frame): a node holding more than `max_leaf` splats is
/// split unless at `max_depth`. With `replicate`, a splat belongs to every cell its disk's bounding
/// box overlaps (conservative); without, to the cell holding its centre. Nodes are laid out breadth
/// first, the 8 children of a node together in Morton order (pool_layout.h).
inline TestOctree build_test_octree(const std::vector<pool::Splat>& splats, const D3& root_min,
                                    double root_size, std::uint32_t max_leaf, std::uint32_t max_depth,
                                    bool replicate = true) {
    struct Cell {
        std::uint32_t level;
        std::uint64_t c[3];
        std::vector<std::uint32_t> members;
    };
    auto cell_bounds = [&](const Cell& cell, double lo[3], double hi[3]) {
        const double s = root_size / static_cast<double>(1ull << cell.level);
        for (int a = 0; a < 3; ++a) {
            lo[a] = root_min[a] + s * static_cast<double>(cell.c[a]);
            hi[a] = root_min[a] + s * static_cast<double>(cell.c[a] + 1);
        }
    };
    auto belongs = [&](const pool::Splat& sp, const Cell& cell) {
        double lo[3], hi[3];
        cell_bounds(cell, lo, hi);
        const double p[3] = {sp.position.x, sp.position.y, sp.position.z};
        const double n[3] = {sp.normal.x, sp.normal.y, sp.normal.z};
        for (int a = 0; a < 3; ++a) {
            if (replicate) {
                // Plus a margin of 1e-6 of the root: a flat floor lying on a cell boundary (its discs'
                // extent 0 along the axis) goes into both cells, so the float walk, whose boundary
                // rounds either way, finds it (without it a floor on the root's mid-plane had holes).
                // At most 1 % of the cell, so deep cells (below 1e-6 of the root) still split their
                // points: a margin larger than the cell put every deep point in every deep cell.
                const double e = sp.radius * std::sqrt(std::max(0.0, 1.0 - n[a] * n[a])) * (1.0 + 1e-6) +
                                 std::min(1e-6 * root_size, 1e-2 * (hi[a] - lo[a]));
                if (p[a] + e < lo[a] || p[a] - e > hi[a]) return false;
            } else {
                const bool last = cell.c[a] + 1 == (1ull << cell.level);
                if (p[a] < lo[a] || (last ? p[a] > hi[a] : p[a] >= hi[a])) return false;
            }
        }
        return true;
    };
    TestOctree t;
    t.info.root_min[0] = static_cast<float>(root_min[0]);
    t.info.root_min[1] = static_cast<float>(root_min[1]);
    t.info.root_min[2] = static_cast<float>(root_min[2]);
    t.info.root_size = static_cast<float>(root_size);
    t.info.max_leaf_splats = max_leaf;
    t.info.flags = replicate ? pool::k_octree_replicated : 0u;
    t.info.unique_splats = splats.size();
    std::deque<Cell> queue;
    Cell root{0, {0, 0, 0}, {}};
    for (std::uint32_t i = 0; i < splats.size(); ++i)
        if (belongs(splats[i], root)) root.members.push_back(i);
    queue.push_back(std::move(root));
    t.nodes.push_back(0);  // root slot
    std::vector<std::uint32_t> slots{0};
    std::size_t head = 0;
    while (!queue.empty()) {
        Cell cell = std::move(queue.front());
        queue.pop_front();
        const std::uint32_t slot = slots[head++];
        t.info.depth = std::max(t.info.depth, cell.level);
        if (cell.members.size() > max_leaf && cell.level < max_depth) {
            const std::uint32_t first = static_cast<std::uint32_t>(t.nodes.size());
            t.nodes[slot] = pool::make_node(pool::NodeType::internal, first);
            for (std::uint32_t c = 0; c < 8; ++c) {
                Cell child{
                    cell.level + 1,
                    {cell.c[0] * 2 + (c & 1), cell.c[1] * 2 + ((c >> 1) & 1), cell.c[2] * 2 + ((c >> 2) & 1)},
                    {}};
                for (std::uint32_t i : cell.members)
                    if (belongs(splats[i], child)) child.members.push_back(i);
                t.nodes.push_back(0);
                slots.push_back(first + c);
                queue.push_back(std::move(child));
            }
        } else if (cell.members.empty()) {
            t.nodes[slot] = pool::make_node(pool::NodeType::empty_leaf, 0);
            t.leaves.push_back({slot, cell.level, {cell.c[0], cell.c[1], cell.c[2]}, false});
        } else {
            const std::uint32_t a = static_cast<std::uint32_t>(t.leaf_info.size());
            t.nodes[slot] = pool::make_node(pool::NodeType::filled_leaf, a);
            t.leaf_info.push_back(static_cast<std::uint32_t>(t.splats.size()));
            for (std::uint32_t i : cell.members) t.splats.push_back(splats[i]);
            t.leaves.push_back({slot, cell.level, {cell.c[0], cell.c[1], cell.c[2]}, true});
        }
    }
    t.leaf_info.push_back(static_cast<std::uint32_t>(t.splats.size()));
    t.info.node_count = static_cast<std::uint32_t>(t.nodes.size());
    t.info.filled_leaves = static_cast<std::uint32_t>(t.leaf_info.size() - 1);
    t.info.splat_count = t.splats.size();
    return t;
}

/// Pool contents for a point set placed with its local origin at `origin` (world, double).
struct TestModel {
    D3 origin{0, 0, 0};
    std::vector<pool::Float3> positions, normals;
    std::vector<float> radii;
    std::vector<pool::Rgba8> colors;
    std::vector<pool::Splat> splats;  ///< one per point, local frame
    TestOctree octree;
};

/// Converts world points into a model with local origin `origin` and builds its octree (root: the
/// bounding cube of all disks, slightly enlarged).
inline TestModel make_model(const std::vector<TestPoint>& pts, const D3& origin, std::uint32_t max_leaf = 48,
                            std::uint32_t max_depth = 10, bool replicate = true) {
    TestModel m;
    m.origin = origin;
    D3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (std::uint32_t i = 0; i < pts.size(); ++i) {
        const TestPoint& p = pts[i];
        const D3 l = d3_sub(p.position, origin);
        const pool::Float3 lf{static_cast<float>(l[0]), static_cast<float>(l[1]), static_cast<float>(l[2])};
        const pool::Float3 nf{static_cast<float>(p.normal[0]), static_cast<float>(p.normal[1]),
                              static_cast<float>(p.normal[2])};
        m.positions.push_back(lf);
        m.normals.push_back(nf);
        m.radii.push_back(static_cast<float>(p.radius));
        m.colors.push_back(p.color);
        m.splats.push_back(pool::Splat{lf, static_cast<float>(p.radius), nf, i});
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], l[a] - p.radius);
            hi[a] = std::max(hi[a], l[a] + p.radius);
        }
    }
    const double size = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}) * 1.01;
    const D3 c = d3_mul(d3_add(lo, hi), 0.5);
    const D3 root_min = d3_sub(c, {size / 2, size / 2, size / 2});
    m.octree = build_test_octree(m.splats, root_min, size, max_leaf, max_depth, replicate);
    return m;
}

/// An in-memory validated pool holding a model's point and octree sections.
inline std::shared_ptr<const pool::PoolFile> make_pool(const TestModel& m, bool with_colors = true) {
    pool::PoolWriter w;
    pool::ModelInfo info{};
    for (int a = 0; a < 3; ++a) info.origin[a] = m.origin[a];
    pool::set_point_bounds(info, m.positions);
    info.flags = pool::k_model_synthetic;
    w.add_array(pool::SectionType::model_info, std::vector<pool::ModelInfo>{info});
    w.add_array(pool::SectionType::positions, m.positions);
    w.add_array(pool::SectionType::normals, m.normals);
    w.add_array(pool::SectionType::radii, m.radii);
    if (with_colors) w.add_array(pool::SectionType::colors, m.colors);
    w.add_array(pool::SectionType::octree_info, std::vector<pool::OctreeInfo>{m.octree.info});
    w.add_array(pool::SectionType::octree_nodes, m.octree.nodes);
    w.add_array(pool::SectionType::leaf_info, m.octree.leaf_info);
    w.add_array(pool::SectionType::splats, m.octree.splats);
    return std::make_shared<const pool::PoolFile>(pool::PoolFile::from_bytes(w.serialize(), "test model"));
}

/// Writes a copy of pool `p` (e.g. make_pool's) to `path`; PoolWriter::carry_over keeps views into
/// `p`, which outlives the write here.
inline void write_pool(const pool::PoolFile& p, const std::filesystem::path& path) {
    pool::PoolWriter w;
    w.carry_over(p);
    w.write(path);
}

}  // namespace prt::test
