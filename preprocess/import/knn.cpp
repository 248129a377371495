#include "knn.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <thread>

#include "parallel.h"

namespace prt::pre::import {

namespace {

/// The k best candidates so far, sorted by (squared distance, index): a fixed order, so the result
/// does not depend on the order in which the tree visits equally distant points.
struct Best {
    std::uint32_t k;
    std::uint32_t count = 0;
    std::uint32_t* index;
    float* distance2;

    float worst() const { return count < k ? std::numeric_limits<float>::infinity() : distance2[k - 1]; }
    void offer(float d2, std::uint32_t i) {
        if (count == k && (d2 > distance2[k - 1] || (d2 == distance2[k - 1] && i > index[k - 1]))) return;
        std::uint32_t at = count < k ? count++ : k - 1;
        while (at > 0 && (distance2[at - 1] > d2 || (distance2[at - 1] == d2 && index[at - 1] > i))) {
            distance2[at] = distance2[at - 1];
            index[at] = index[at - 1];
            --at;
        }
        distance2[at] = d2;
        index[at] = i;
    }
};

}  // namespace

KdTree::KdTree(const std::vector<std::array<double, 3>>& positions, unsigned threads) {
    const std::size_t n = positions.size();
    if (n == 0) return;
    double lo[3] = {positions[0][0], positions[0][1], positions[0][2]}, hi[3] = {lo[0], lo[1], lo[2]};
    for (const auto& p : positions)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], p[a]);
            hi[a] = std::max(hi[a], p[a]);
        }
    const double centre[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    m_points.resize(n);
    for (std::size_t i = 0; i < n; ++i)
        m_points[i] = {static_cast<float>(positions[i][0] - centre[0]),
                       static_cast<float>(positions[i][1] - centre[1]),
                       static_cast<float>(positions[i][2] - centre[2]), static_cast<std::uint32_t>(i)};
    m_depth = 0;
    while (((n + (std::size_t{1} << m_depth) - 1) >> m_depth) > k_bucket) ++m_depth;
    const std::size_t internal = (std::size_t{1} << m_depth) - 1;
    m_split.assign(internal, 0.f);
    m_axis.assign(internal, 0);
    // Subtrees of the top levels build on their own threads (2^spawn of them).
    unsigned spawn = 0;
    for (unsigned t = resolve_threads(threads); t > 1 && spawn < 4; t >>= 1) ++spawn;
    build(0, 0, n, 0, n > 65536 ? spawn : 0);
    m_slot.resize(n);
    for (std::size_t s = 0; s < n; ++s) m_slot[m_points[s].index] = static_cast<std::uint32_t>(s);
}

void KdTree::build(std::size_t node, std::size_t begin, std::size_t end, unsigned depth, unsigned spawn) {
    if (depth == m_depth) return;
    float lo[3] = {m_points[begin].x, m_points[begin].y, m_points[begin].z}, hi[3] = {lo[0], lo[1], lo[2]};
    for (std::size_t i = begin; i < end; ++i) {
        const float v[3] = {m_points[i].x, m_points[i].y, m_points[i].z};
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], v[a]);
            hi[a] = std::max(hi[a], v[a]);
        }
    }
    int axis = 0;
    for (int a = 1; a < 3; ++a)
        if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
    const std::size_t mid = begin + (end - begin) / 2;
    auto coord = [axis](const Point& p) { return axis == 0 ? p.x : axis == 1 ? p.y : p.z; };
    std::nth_element(m_points.begin() + static_cast<std::ptrdiff_t>(begin),
                     m_points.begin() + static_cast<std::ptrdiff_t>(mid),
                     m_points.begin() + static_cast<std::ptrdiff_t>(end),
                     [&](const Point& a, const Point& b) { return coord(a) < coord(b); });
    m_split[node] = coord(m_points[mid]);
    m_axis[node] = static_cast<std::uint8_t>(axis);
    if (spawn > 0) {
        std::thread left([&] { build(2 * node + 1, begin, mid, depth + 1, spawn - 1); });
        build(2 * node + 2, mid, end, depth + 1, spawn - 1);
        left.join();
    } else {
        build(2 * node + 1, begin, mid, depth + 1, 0);
        build(2 * node + 2, mid, end, depth + 1, 0);
    }
}

namespace {

/// One query's state: incremental distance to the cells (Arya & Mount 1993, "Algorithms for fast
/// vector quantization": the squared distance from q to a cell is the sum of the per-axis offsets
/// to the planes crossed on the way down, which prunes better than the last plane alone).
struct Query {
    const float* q;
    std::uint32_t self;
    const std::uint8_t* excluded;
    Best* best;
};

}  // namespace

void KdTree::descend(const void* query_state, std::size_t node, std::size_t begin, std::size_t end,
                     unsigned depth, float rd, float* off) const {
    const Query& st = *static_cast<const Query*>(query_state);
    Best& best = *st.best;
    if (depth == m_depth) {
        const float* q = st.q;
        for (std::size_t s = begin; s < end; ++s) {
            const Point& p = m_points[s];
            const float dx = p.x - q[0], dy = p.y - q[1], dz = p.z - q[2];
            const float d2 = dx * dx + dy * dy + dz * dz;
            if (d2 > best.worst()) continue;
            if (p.index == st.self || (st.excluded && st.excluded[p.index])) continue;
            best.offer(d2, p.index);
        }
        return;
    }
    const std::size_t mid = begin + (end - begin) / 2;
    const int axis = m_axis[node];
    const float diff = st.q[axis] - m_split[node];
    const bool left_first = diff < 0;
    if (left_first)
        descend(query_state, 2 * node + 1, begin, mid, depth + 1, rd, off);
    else
        descend(query_state, 2 * node + 2, mid, end, depth + 1, rd, off);
    // The far cell: the offset along this axis grows to |diff| (<=: an equally distant point may
    // win on its index).
    const float old = off[axis];
    const float far_rd = rd - old * old + diff * diff;
    if (far_rd <= best.worst()) {
        off[axis] = diff;
        if (left_first)
            descend(query_state, 2 * node + 2, mid, end, depth + 1, far_rd, off);
        else
            descend(query_state, 2 * node + 1, begin, mid, depth + 1, far_rd, off);
        off[axis] = old;
    }
}

std::uint32_t KdTree::search(const float q[3], std::uint32_t self, std::uint32_t k,
                             const std::uint8_t* excluded, std::uint32_t* index, float* distance2) const {
    if (k == 0 || m_points.empty()) return 0;
    Best best{k, 0, index, distance2};
    const Query st{q, self, excluded, &best};
    float off[3] = {0.f, 0.f, 0.f};
    descend(&st, 0, 0, m_points.size(), 0, 0.f, off);
    return best.count;
}

std::uint32_t KdTree::nearest(std::uint32_t self, std::uint32_t k, const std::uint8_t* excluded,
                              std::uint32_t* index, float* distance2) const {
    const Point& p = m_points[m_slot[self]];
    const float q[3] = {p.x, p.y, p.z};
    return search(q, self, k, excluded, index, distance2);
}

void KdTree::for_each(
    std::uint32_t k, unsigned threads,
    const std::function<void(std::uint32_t, const std::uint32_t*, const float*, std::uint32_t)>& visit,
    const std::function<void(std::uint64_t)>& progress) const {
    const std::size_t n = m_points.size();
    std::atomic<std::uint64_t> done{0};
    parallel_chunks(n, 4096, resolve_threads(threads), [&](std::size_t b, std::size_t e, unsigned worker) {
        std::vector<std::uint32_t> index(k);
        std::vector<float> distance2(k);
        for (std::size_t s = b; s < e; ++s) {
            const Point& p = m_points[s];
            const float q[3] = {p.x, p.y, p.z};
            const std::uint32_t found = search(q, p.index, k, nullptr, index.data(), distance2.data());
            visit(p.index, index.data(), distance2.data(), found);
        }
        const std::uint64_t total = done.fetch_add(e - b) + (e - b);
        if (worker == 0 && progress) progress(total);
    });
}

}  // namespace prt::pre::import
