// PointRT preprocess: the BVH over the MLS kd-tree's non-empty leaves (mls_bvh.h).
#include "mls_bvh.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "float_round.h"
#include "prt/error.h"
#include "prt/tool_util.h"

namespace prt::mls {

namespace {

constexpr double k_inf = std::numeric_limits<double>::infinity();

struct DBox {
    double lo[3] = {k_inf, k_inf, k_inf};
    double hi[3] = {-k_inf, -k_inf, -k_inf};
    void grow(const DBox& b) {
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], b.lo[a]);
            hi[a] = std::max(hi[a], b.hi[a]);
        }
    }
    double half_area() const {
        if (!(hi[0] >= lo[0])) return 0.0;
        const double x = hi[0] - lo[0], y = hi[1] - lo[1], z = hi[2] - lo[2];
        return x * y + y * z + z * x;
    }
};

/// The non-empty kd leaves with their cells, in kd order (the walk the validator repeats).
void collect_leaves(const MlsModel& m, std::vector<pool::MlsBvhLeaf>& leaves) {
    struct Item {
        std::uint32_t node;
        float lo[3], hi[3];
    };
    Item root{0, {}, {}};
    std::copy(m.info.root_lo, m.info.root_lo + 3, root.lo);
    std::copy(m.info.root_hi, m.info.root_hi + 3, root.hi);
    std::vector<Item> stack{root};
    while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        const pool::MlsNode& n = m.nodes[it.node];
        if (pool::mls_node_is_leaf(n)) {
            if (pool::mls_leaf_count(n) == 0) continue;
            pool::MlsBvhLeaf l{};
            std::copy(it.lo, it.lo + 3, l.lo);
            std::copy(it.hi, it.hi + 3, l.hi);
            l.first = pool::mls_leaf_first(n);
            l.count = pool::mls_leaf_count(n);
            leaves.push_back(l);
            continue;
        }
        const std::uint32_t axis = pool::mls_node_axis(n), left = pool::mls_node_left(n);
        const float split = std::bit_cast<float>(n.payload);
        Item l = it, r = it;
        l.node = left;
        r.node = left + 1;
        l.hi[axis] = split;
        r.lo[axis] = split;
        stack.push_back(r);
        stack.push_back(l);
    }
}

/// A leaf's box: its cell cut to the box of its splats' support balls (the ray meets the supports
/// only there, so sampling never starts outside it; mls_support_span).
DBox leaf_box(const MlsModel& m, const pool::MlsBvhLeaf& l) {
    DBox b;
    for (std::uint32_t r = l.first; r < l.first + l.count; ++r) {
        const pool::MlsSplat& sp = m.splats[m.refs[r]];
        const double rad = 1.0 / double(sp.inv_support);
        const double p[3] = {sp.position.x, sp.position.y, sp.position.z};
        for (int a = 0; a < 3; ++a) {
            b.lo[a] = std::min(b.lo[a], p[a] - rad);
            b.hi[a] = std::max(b.hi[a], p[a] + rad);
        }
    }
    for (int a = 0; a < 3; ++a) {
        b.lo[a] = std::max(b.lo[a], double(l.lo[a]));
        b.hi[a] = std::min(b.hi[a], double(l.hi[a]));
        // A support ball only touching the cell leaves a flat box; never an inverted one.
        if (b.hi[a] < b.lo[a]) b.hi[a] = b.lo[a];
    }
    return b;
}

class Builder {
public:
    Builder(const std::vector<DBox>& boxes, std::vector<pool::MlsBvhNode>& out) : m_boxes(boxes), m_out(out) {
        m_centre.resize(boxes.size() * 3);
        for (std::size_t i = 0; i < boxes.size(); ++i)
            for (int a = 0; a < 3; ++a) m_centre[i * 3 + a] = 0.5 * (boxes[i].lo[a] + boxes[i].hi[a]);
        m_index.resize(boxes.size());
        for (std::size_t i = 0; i < boxes.size(); ++i) m_index[i] = static_cast<std::uint32_t>(i);
    }

    /// Builds the subtree over m_index[a, e) (at least two leaves) into node `slot`.
    void build(std::size_t a, std::size_t e, std::uint32_t slot, std::uint32_t depth) {
        m_depth = std::max(m_depth, depth);
        const std::size_t m = split(a, e, depth);
        const std::size_t range[2][2] = {{a, m}, {m, e}};
        for (int c = 0; c < 2; ++c) {
            const std::size_t ca = range[c][0], ce = range[c][1];
            DBox b;
            for (std::size_t i = ca; i < ce; ++i) b.grow(m_boxes[m_index[i]]);
            pool::MlsBvhChild& ch = m_out[slot].child[c];
            for (int k = 0; k < 3; ++k) {
                ch.lo[k] = pre::round_down(b.lo[k]);  // outwards: the stored box holds the double one
                ch.hi[k] = pre::round_up(b.hi[k]);
            }
            ch.reserved = 0;
            if (ce - ca == 1) {
                ch.ref = pool::k_mls_bvh_leaf_bit | m_index[ca];
                continue;
            }
            const auto node = static_cast<std::uint32_t>(m_out.size());
            ch.ref = node;
            m_out.emplace_back();
            build(ca, ce, node, depth + 1);
        }
    }

    std::uint32_t depth() const { return m_depth; }

private:
    static constexpr int k_bins = 16;

    /// The SAH split of [a, e) over 16 centroid bins per axis (Wald 2007); below level 32, or where
    /// every centroid is the same, halves by count (the median along the widest centroid axis).
    std::size_t split(std::size_t a, std::size_t e, std::uint32_t depth) {
        DBox cb;
        for (std::size_t i = a; i < e; ++i) {
            const double* c = &m_centre[std::size_t{m_index[i]} * 3];
            DBox p;
            for (int k = 0; k < 3; ++k) p.lo[k] = p.hi[k] = c[k];
            cb.grow(p);
        }
        int best_axis = -1, best_bin = 0;
        double best_cost = k_inf;
        const std::size_t n = e - a;
        if (depth < 32) {
            for (int axis = 0; axis < 3; ++axis) {
                const double lo = cb.lo[axis], ext = cb.hi[axis] - cb.lo[axis];
                if (!(ext > 0.0)) continue;
                std::array<DBox, k_bins> bins{};
                std::array<std::size_t, k_bins> count{};
                for (std::size_t i = a; i < e; ++i) {
                    const int b = bin_of(m_index[i], axis, lo, ext);
                    bins[b].grow(m_boxes[m_index[i]]);
                    ++count[b];
                }
                std::array<double, k_bins> right_cost{};
                DBox r;
                std::size_t rc = 0;
                for (int b = k_bins - 1; b > 0; --b) {
                    r.grow(bins[b]);
                    rc += count[b];
                    right_cost[b] = r.half_area() * double(rc);
                }
                DBox l;
                std::size_t lc = 0;
                for (int b = 0; b + 1 < k_bins; ++b) {
                    l.grow(bins[b]);
                    lc += count[b];
                    if (lc == 0 || lc == n) continue;
                    const double cost = l.half_area() * double(lc) + right_cost[b + 1];
                    if (cost < best_cost) {
                        best_cost = cost;
                        best_axis = axis;
                        best_bin = b + 1;
                    }
                }
            }
        }
        auto first = m_index.begin() + static_cast<std::ptrdiff_t>(a);
        auto last = m_index.begin() + static_cast<std::ptrdiff_t>(e);
        if (best_axis >= 0) {
            const double lo = cb.lo[best_axis], ext = cb.hi[best_axis] - cb.lo[best_axis];
            const auto mid = std::partition(
                first, last, [&](std::uint32_t i) { return bin_of(i, best_axis, lo, ext) < best_bin; });
            return static_cast<std::size_t>(mid - m_index.begin());
        }
        int axis = 0;
        for (int k = 1; k < 3; ++k)
            if (cb.hi[k] - cb.lo[k] > cb.hi[axis] - cb.lo[axis]) axis = k;
        const auto mid = first + static_cast<std::ptrdiff_t>(n / 2);
        std::nth_element(first, mid, last, [&](std::uint32_t x, std::uint32_t y) {
            return m_centre[std::size_t{x} * 3 + axis] < m_centre[std::size_t{y} * 3 + axis];
        });
        return a + n / 2;
    }

    int bin_of(std::uint32_t i, int axis, double lo, double ext) const {
        const int b = static_cast<int>((m_centre[std::size_t{i} * 3 + axis] - lo) / ext * k_bins);
        return std::clamp(b, 0, k_bins - 1);
    }

    const std::vector<DBox>& m_boxes;
    std::vector<pool::MlsBvhNode>& m_out;
    std::vector<double> m_centre;
    std::vector<std::uint32_t> m_index;
    std::uint32_t m_depth = 0;
};

}  // namespace

void build_mls_bvh(MlsModel& model) {
    const double t0 = tool::now_seconds();
    model.bvh_nodes.clear();
    model.bvh_leaves.clear();
    model.info.bvh_depth = 0;
    collect_leaves(model, model.bvh_leaves);
    if (model.bvh_leaves.size() < 2) {
        model.bvh_leaves.clear();
        model.stats.seconds_bvh = tool::now_seconds() - t0;
        return;
    }
    if (model.bvh_leaves.size() > pool::k_mls_bvh_leaf_bit)
        throw Error("MLS build: more non-empty leaves than the BVH layout holds (2^31)");
    std::vector<DBox> boxes(model.bvh_leaves.size());
    for (std::size_t i = 0; i < boxes.size(); ++i) boxes[i] = leaf_box(model, model.bvh_leaves[i]);
    model.bvh_nodes.reserve(boxes.size() - 1);
    model.bvh_nodes.emplace_back();
    Builder b(boxes, model.bvh_nodes);
    b.build(0, boxes.size(), 0, 0);
    if (b.depth() > pool::k_max_mls_bvh_depth)  // halving below level 32 bounds it by 32 + 31
        throw Error("MLS build: BVH depth " + std::to_string(b.depth()) + " exceeds " +
                    std::to_string(pool::k_max_mls_bvh_depth));
    model.info.bvh_depth = b.depth();
    model.stats.bvh_nodes = model.bvh_nodes.size();
    model.stats.bvh_depth = b.depth();
    model.stats.seconds_bvh = tool::now_seconds() - t0;
}

}  // namespace prt::mls
