// PointRT preprocess: the one exact k-nearest-neighbour search of the tools (prt-radii's splat radii,
// prt-iso's radii of influence, prt-import's outlier removal, normals and orientation graph,
// prt-fidelity's local point spacing). Host only.
//
// A kd-tree over a fixed point set (Friedman, Bentley & Finkel 1977, "An algorithm for finding best
// matches in logarithmic expected time", ACM TOMS 3(3)): median splits along the widest extent of
// each cell, buckets of at most k_bucket points. The points are copied in the caller's precision T
// (float or double), reordered leaf after leaf so a bucket is contiguous in memory. The shape of the
// tree follows from the point count alone (each node halves its range), so nodes need no pointers.
// Searches carry the squared distance to the current cell incrementally (Arya & Mount 1993,
// "Algorithms for fast vector quantization": the squared distance from q to a cell is the sum of
// the per-axis offsets to the planes crossed on the way down), nearer child first.
//
// Distances are computed as dx * dx + dy * dy + dz * dz in T from the stored coordinates (d = point
// - query), so the k-th distance is exactly the one any exact search in T over the same
// coordinates finds. Equally distant points are ordered by index, so results do not depend on the
// order in which the tree visits them, nor on the thread count.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "prt/parallel.h"

namespace prt::pre {

template <class T>
class KdTree {
public:
    static constexpr std::uint32_t k_bucket = 12;

    /// Builds over `count` points; `coords(i, T out[3])` writes point i's (finite) coordinates.
    /// `threads` 0 = every hardware thread.
    template <class Coords>
    KdTree(std::size_t count, Coords&& coords, unsigned threads = 0) {
        if (count == 0) return;
        m_points.resize(count);
        for (std::size_t i = 0; i < count; ++i) {
            T c[3];
            coords(i, c);
            m_points[i] = {c[0], c[1], c[2], static_cast<std::uint32_t>(i)};
        }
        while (((count + (std::size_t{1} << m_depth) - 1) >> m_depth) > k_bucket) ++m_depth;
        const std::size_t internal = (std::size_t{1} << m_depth) - 1;
        m_split.assign(internal, T(0));
        m_axis.assign(internal, 0);
        build_parallel(threads);
        m_slot.resize(count);
        for (std::size_t s = 0; s < count; ++s) m_slot[m_points[s].index] = static_cast<std::uint32_t>(s);
    }

    std::size_t size() const { return m_points.size(); }

    /// Point i's coordinates as stored.
    std::array<T, 3> point(std::uint32_t i) const {
        const Point& p = m_points[m_slot[i]];
        return {p.x, p.y, p.z};
    }

    /// The (up to) k points nearest to q other than point `skip` (~0u: none) and points i with
    /// `excluded[i]` set (when not null): their indices in `index` and squared distances in
    /// `distance2`, nearest first (ties: smaller index first). Returns how many were found (< k
    /// only when the set has fewer eligible points).
    std::uint32_t search(const T q[3], std::uint32_t skip, std::uint32_t k, const std::uint8_t* excluded,
                         std::uint32_t* index, T* distance2) const {
        if (k == 0 || m_points.empty()) return 0;
        Best best{k, 0, index, distance2};
        const Query query{q, skip, excluded, &best};
        T off[3] = {0, 0, 0};
        descend(query, 0, 0, m_points.size(), 0, T(0), off);
        return best.count;
    }

    /// search() from point `self`, skipping itself.
    std::uint32_t nearest(std::uint32_t self, std::uint32_t k, const std::uint8_t* excluded,
                          std::uint32_t* index, T* distance2) const {
        const Point& p = m_points[m_slot[self]];
        const T q[3] = {p.x, p.y, p.z};
        return search(q, self, k, excluded, index, distance2);
    }

    /// Calls `visit(i, index, distance2, found)` for every point i with its k nearest other points
    /// (as nearest()), in parallel over `threads` workers (0 = all), in the tree's order (queries
    /// near each other in space run one after another, which keeps the tree in cache). `visit` must
    /// be safe to call concurrently for different points; `progress(done)`, when set, is called
    /// from one worker.
    template <class Visit>
    void for_each(std::uint32_t k, unsigned threads, Visit&& visit,
                  const std::function<void(std::uint64_t)>& progress = {}) const {
        std::atomic<std::uint64_t> done{0};
        parallel_chunks(m_points.size(), 4096, resolve_threads(threads),
                        [&](std::size_t b, std::size_t e, unsigned worker) {
                            std::vector<std::uint32_t> index(k);
                            std::vector<T> distance2(k);
                            for (std::size_t s = b; s < e; ++s) {
                                const Point& p = m_points[s];
                                const T q[3] = {p.x, p.y, p.z};
                                const std::uint32_t found =
                                    search(q, p.index, k, nullptr, index.data(), distance2.data());
                                visit(p.index, index.data(), distance2.data(), found);
                            }
                            const std::uint64_t total = done.fetch_add(e - b) + (e - b);
                            if (worker == 0 && progress) progress(total);
                        });
    }

    /// The k best candidates by (squared distance, index), ties broken by the smaller index, in
    /// ascending order (the search's list; the tiled search of tiled_knn.cpp keeps the same).
    struct Best {
        std::uint32_t k;
        std::uint32_t count = 0;
        std::uint32_t* index;
        T* distance2;

        T worst() const { return count < k ? std::numeric_limits<T>::infinity() : distance2[k - 1]; }
        void offer(T d2, std::uint32_t i) {
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

private:
    struct Point {
        T x, y, z;
        std::uint32_t index;  ///< into the original points
    };

    struct Query {
        const T* q;
        std::uint32_t skip;
        const std::uint8_t* excluded;
        Best* best;
    };

    /// Splits node `node` (points [begin, end)) at the median of its widest axis.
    void split(std::size_t node, std::size_t begin, std::size_t end) {
        T lo[3] = {m_points[begin].x, m_points[begin].y, m_points[begin].z}, hi[3] = {lo[0], lo[1], lo[2]};
        for (std::size_t i = begin; i < end; ++i) {
            const T v[3] = {m_points[i].x, m_points[i].y, m_points[i].z};
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
    }

    void build(std::size_t node, std::size_t begin, std::size_t end, unsigned depth) {
        if (depth == m_depth) return;
        split(node, begin, end);
        const std::size_t mid = begin + (end - begin) / 2;
        build(2 * node + 1, begin, mid, depth + 1);
        build(2 * node + 2, mid, end, depth + 1);
    }

    /// The top levels one level at a time, each level's nodes in parallel, then the subtrees below
    /// in parallel (the same tree as a serial build: every split only reorders its own range).
    void build_parallel(unsigned threads) {
        threads = resolve_threads(threads);
        unsigned top = 0;  // levels split level by level: 2^top subtrees below them
        if (m_points.size() > 65536)
            for (unsigned t = threads; t > 1 && top < 4 && top < m_depth; t >>= 1) ++top;
        for (unsigned depth = 0; depth < top; ++depth)
            parallel_chunks(std::size_t{1} << depth, 1, threads, [&](std::size_t b, std::size_t e, unsigned) {
                for (std::size_t j = b; j < e; ++j) {
                    std::size_t begin, end;
                    range(depth, j, begin, end);
                    split((std::size_t{1} << depth) - 1 + j, begin, end);
                }
            });
        parallel_chunks(std::size_t{1} << top, 1, threads, [&](std::size_t b, std::size_t e, unsigned) {
            for (std::size_t j = b; j < e; ++j) {
                std::size_t begin, end;
                range(top, j, begin, end);
                build((std::size_t{1} << top) - 1 + j, begin, end, top);
            }
        });
    }

    /// The point range of the j-th node at `depth` (halving from the root).
    void range(unsigned depth, std::size_t j, std::size_t& begin, std::size_t& end) const {
        begin = 0;
        end = m_points.size();
        for (unsigned d = depth; d-- > 0;) {
            const std::size_t mid = begin + (end - begin) / 2;
            if ((j >> d) & 1u)
                begin = mid;
            else
                end = mid;
        }
    }

    void descend(const Query& query, std::size_t node, std::size_t begin, std::size_t end, unsigned depth,
                 T rd, T* off) const {
        Best& best = *query.best;
        if (depth == m_depth) {
            const T* q = query.q;
            for (std::size_t s = begin; s < end; ++s) {
                const Point& p = m_points[s];
                const T dx = p.x - q[0], dy = p.y - q[1], dz = p.z - q[2];
                const T d2 = dx * dx + dy * dy + dz * dz;
                if (d2 > best.worst()) continue;
                if (p.index == query.skip || (query.excluded && query.excluded[p.index])) continue;
                best.offer(d2, p.index);
            }
            return;
        }
        const std::size_t mid = begin + (end - begin) / 2;
        const int axis = m_axis[node];
        const T diff = query.q[axis] - m_split[node];
        const bool left_first = diff < 0;
        if (left_first)
            descend(query, 2 * node + 1, begin, mid, depth + 1, rd, off);
        else
            descend(query, 2 * node + 2, mid, end, depth + 1, rd, off);
        // The far cell: the offset along this axis grows to |diff| (<=: an equally distant point may
        // win on its index).
        const T old = off[axis];
        const T far_rd = rd - old * old + diff * diff;
        if (far_rd <= best.worst()) {
            off[axis] = diff;
            if (left_first)
                descend(query, 2 * node + 2, mid, end, depth + 1, far_rd, off);
            else
                descend(query, 2 * node + 1, begin, mid, depth + 1, far_rd, off);
            off[axis] = old;
        }
    }

    std::vector<Point> m_points;  ///< leaf order
    std::vector<T> m_split;       ///< per internal node (heap order: children 2i+1, 2i+2)
    std::vector<std::uint8_t> m_axis;
    std::vector<std::uint32_t> m_slot;  ///< original index -> position in m_points
    unsigned m_depth = 0;               ///< internal levels; nodes at this depth are buckets
};

}  // namespace prt::pre
