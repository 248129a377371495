#include "point_spacing.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "parallel.h"
#include "prt/error.h"

namespace prt::bench {

namespace {

constexpr std::uint32_t k_leaf_points = 8;

double box_distance_sq(const double lo[3], const double hi[3], const P3& q) {
    double d = 0;
    for (int a = 0; a < 3; ++a) {
        const double e = q[a] < lo[a] ? lo[a] - q[a] : q[a] > hi[a] ? q[a] - hi[a] : 0.0;
        d += e * e;
    }
    return d;
}

double distance_sq(const P3& a, const P3& b) {
    const double x = a[0] - b[0], y = a[1] - b[1], z = a[2] - b[2];
    return x * x + y * y + z * z;
}

}  // namespace

PointIndex::PointIndex(std::vector<P3> points) : m_points(std::move(points)) {
    if (m_points.size() < 2) throw Error("point index: need at least 2 points");
    if (m_points.size() >= 0xffffffffu) throw Error("point index: too many points");
    for (const P3& p : m_points)
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
            throw Error("point index: a point is not finite");
    m_order.resize(m_points.size());
    for (std::uint32_t i = 0; i < m_order.size(); ++i) m_order[i] = i;
    m_nodes.reserve(4 * m_points.size() / k_leaf_points + 2);
    m_nodes.push_back(Node{{}, {}, 0, std::uint32_t(m_points.size()), 0});
    // Top down with an explicit work list: box, then split at the median of the longest axis.
    std::vector<std::uint32_t> work{0};
    while (!work.empty()) {
        const std::uint32_t ni = work.back();
        work.pop_back();
        Node& n = m_nodes[ni];
        for (int a = 0; a < 3; ++a) n.lo[a] = std::numeric_limits<double>::infinity(), n.hi[a] = -n.lo[a];
        for (std::uint32_t i = n.begin; i < n.end; ++i)
            for (int a = 0; a < 3; ++a) {
                n.lo[a] = std::min(n.lo[a], m_points[m_order[i]][a]);
                n.hi[a] = std::max(n.hi[a], m_points[m_order[i]][a]);
            }
        if (n.end - n.begin <= k_leaf_points) continue;
        int axis = 0;
        for (int a = 1; a < 3; ++a)
            if (n.hi[a] - n.lo[a] > n.hi[axis] - n.lo[axis]) axis = a;
        const std::uint32_t begin = n.begin, end = n.end, mid = begin + (end - begin) / 2;
        std::nth_element(
            m_order.begin() + begin, m_order.begin() + mid, m_order.begin() + end,
            [&](std::uint32_t a, std::uint32_t b) { return m_points[a][axis] < m_points[b][axis]; });
        const std::uint32_t left = std::uint32_t(m_nodes.size());
        m_nodes[ni].left = left;  // n may dangle after the pushes below
        m_nodes.push_back(Node{{}, {}, begin, mid, 0});
        m_nodes.push_back(Node{{}, {}, mid, end, 0});
        work.push_back(left);
        work.push_back(left + 1);
    }
}

std::uint32_t PointIndex::nearest(const P3& q, double& distance) const {
    double best = std::numeric_limits<double>::infinity();
    std::uint32_t best_i = 0;
    std::uint32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& n = m_nodes[stack[--top]];
        if (box_distance_sq(n.lo, n.hi, q) >= best) continue;
        if (n.left == 0) {
            for (std::uint32_t i = n.begin; i < n.end; ++i) {
                const double d = distance_sq(m_points[m_order[i]], q);
                if (d < best) best = d, best_i = m_order[i];
            }
            continue;
        }
        // nearer child last, so it is searched first
        const Node &a = m_nodes[n.left], &b = m_nodes[n.left + 1];
        const bool a_first = box_distance_sq(a.lo, a.hi, q) <= box_distance_sq(b.lo, b.hi, q);
        stack[top++] = a_first ? n.left + 1 : n.left;
        stack[top++] = a_first ? n.left : n.left + 1;
    }
    distance = std::sqrt(best);
    return best_i;
}

void PointIndex::knn(const P3& q, std::uint32_t k, std::uint32_t skip, std::vector<double>& out) const {
    std::vector<std::uint32_t> idx;
    knn_indices(q, skip == ~0u ? k : k + 1, idx);
    out.clear();
    for (std::uint32_t i : idx)
        if (i != skip && out.size() < k) out.push_back(std::sqrt(distance_sq(m_points[i], q)));
}

void PointIndex::knn_indices(const P3& q, std::uint32_t k, std::vector<std::uint32_t>& out) const {
    // (distance^2, index) pairs in a max-heap of at most k
    std::vector<std::pair<double, std::uint32_t>> heap;
    auto worst = [&] {
        return heap.size() < k ? std::numeric_limits<double>::infinity() : heap.front().first;
    };
    std::uint32_t stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& n = m_nodes[stack[--top]];
        if (box_distance_sq(n.lo, n.hi, q) >= worst()) continue;
        if (n.left == 0) {
            for (std::uint32_t i = n.begin; i < n.end; ++i) {
                const double d = distance_sq(m_points[m_order[i]], q);
                if (heap.size() < k) {
                    heap.push_back({d, m_order[i]});
                    std::push_heap(heap.begin(), heap.end());
                } else if (d < heap.front().first) {
                    std::pop_heap(heap.begin(), heap.end());
                    heap.back() = {d, m_order[i]};
                    std::push_heap(heap.begin(), heap.end());
                }
            }
            continue;
        }
        const Node &a = m_nodes[n.left], &b = m_nodes[n.left + 1];
        const bool a_first = box_distance_sq(a.lo, a.hi, q) <= box_distance_sq(b.lo, b.hi, q);
        stack[top++] = a_first ? n.left + 1 : n.left;
        stack[top++] = a_first ? n.left : n.left + 1;
    }
    std::sort(heap.begin(), heap.end());
    out.clear();
    for (const auto& e : heap) out.push_back(e.second);
}

std::vector<double> PointIndex::local_spacing(unsigned threads) const {
    std::vector<double> s(m_points.size());
    const double factor = std::sqrt(M_PI / double(k_spacing_neighbours));
    pre::parallel_chunks(m_points.size(), 4096, pre::resolve_threads(threads),
                         [&](std::size_t b, std::size_t e, unsigned) {
                             std::vector<double> d;
                             for (std::size_t i = b; i < e; ++i) {
                                 knn(m_points[i], k_spacing_neighbours, std::uint32_t(i), d);
                                 s[i] = d.empty() ? 0.0 : d.back() * factor;
                             }
                         });
    return s;
}

}  // namespace prt::bench
