#include <algorithm>
#include <cmath>
#include <numeric>

#include "orient.h"
#include "progress.h"

namespace prt::pre::import {

namespace {

inline bool valid(const pool::Float3& n) {
    const float l = n.x * n.x + n.y * n.y + n.z * n.z;
    return std::isfinite(l) && l > 1e-12f;
}
inline float dot(const pool::Float3& a, const pool::Float3& b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline void flip(pool::Float3& n) {
    n = {-n.x, -n.y, -n.z};
}

/// Max-heap of points keyed by their best edge weight so far, with increase-key (eager Prim):
/// at most one entry per point, so memory stays O(n) however dense the graph is.
class IndexedMaxHeap {
public:
    explicit IndexedMaxHeap(std::size_t n) : m_pos(n, -1), m_key(n, 0.f) {}
    bool empty() const { return m_heap.empty(); }
    bool contains(std::uint32_t v) const { return m_pos[v] >= 0; }
    float key(std::uint32_t v) const { return m_key[v]; }
    void push_or_raise(std::uint32_t v, float key) {
        if (m_pos[v] < 0) {
            m_key[v] = key;
            m_pos[v] = static_cast<std::int64_t>(m_heap.size());
            m_heap.push_back(v);
            up(m_heap.size() - 1);
        } else if (key > m_key[v]) {
            m_key[v] = key;
            up(static_cast<std::size_t>(m_pos[v]));
        }
    }
    std::uint32_t pop() {
        const std::uint32_t top = m_heap.front();
        m_pos[top] = -1;
        const std::uint32_t last = m_heap.back();
        m_heap.pop_back();
        if (!m_heap.empty()) {
            m_heap[0] = last;
            m_pos[last] = 0;
            down(0);
        }
        return top;
    }

private:
    void place(std::size_t i, std::uint32_t v) {
        m_heap[i] = v;
        m_pos[v] = static_cast<std::int64_t>(i);
    }
    void up(std::size_t i) {
        const std::uint32_t v = m_heap[i];
        while (i > 0) {
            const std::size_t parent = (i - 1) / 2;
            if (m_key[m_heap[parent]] >= m_key[v]) break;
            place(i, m_heap[parent]);
            i = parent;
        }
        place(i, v);
    }
    void down(std::size_t i) {
        const std::uint32_t v = m_heap[i];
        const std::size_t n = m_heap.size();
        while (true) {
            std::size_t child = 2 * i + 1;
            if (child >= n) break;
            if (child + 1 < n && m_key[m_heap[child + 1]] > m_key[m_heap[child]]) ++child;
            if (m_key[m_heap[child]] <= m_key[v]) break;
            place(i, m_heap[child]);
            i = child;
        }
        place(i, v);
    }

    std::vector<std::uint32_t> m_heap;
    std::vector<std::int64_t> m_pos;
    std::vector<float> m_key;
};

}  // namespace

OrientStats orient_by_propagation(const std::vector<std::array<double, 3>>& positions,
                                  std::vector<pool::Float3>& normals, const KnnGraph& graph, bool quiet,
                                  const std::vector<std::uint8_t>* fixed,
                                  std::vector<std::uint32_t>* component) {
    OrientStats stats;
    const std::size_t n = normals.size();
    const std::uint32_t k = graph.k;
    std::vector<std::uint8_t> ok(n);
    for (std::size_t i = 0; i < n; ++i) {
        ok[i] = valid(normals[i]);
        if (!ok[i]) ++stats.skipped;
    }

    // Symmetric adjacency (CSR): k-NN is not symmetric, and a point must be reachable from every
    // point that lists it as a neighbour or the graph splits into needless components.
    std::vector<std::uint64_t> begin(n + 1, 0);
    auto each_edge = [&](auto&& fn) {
        for (std::size_t i = 0; i < n; ++i) {
            if (!ok[i]) continue;
            for (std::uint32_t j = 0; j < k; ++j) {
                const std::uint32_t m = graph.neighbours[i * k + j];
                if (m == k_no_neighbour || m == i || m >= n || !ok[m]) continue;
                fn(static_cast<std::uint32_t>(i), m);
            }
        }
    };
    each_edge([&](std::uint32_t a, std::uint32_t b) {
        ++begin[a + 1];
        ++begin[b + 1];
    });
    std::partial_sum(begin.begin(), begin.end(), begin.begin());
    std::vector<std::uint32_t> adjacent(begin[n]);
    {
        std::vector<std::uint64_t> fill(begin.begin(), begin.end() - 1);
        each_edge([&](std::uint32_t a, std::uint32_t b) {
            adjacent[fill[a]++] = b;
            adjacent[fill[b]++] = a;
        });
    }

    std::vector<std::uint8_t> visited(n, 0);
    if (component) component->assign(n, 0);
    std::vector<std::uint32_t> parent(n, k_no_neighbour);
    IndexedMaxHeap heap(n);
    LazyProgress progress("orienting normals", n, quiet);
    std::uint64_t done = 0;
    auto push_neighbours = [&](std::uint32_t v) {
        for (std::uint64_t e = begin[v]; e < begin[v + 1]; ++e) {
            const std::uint32_t m = adjacent[e];
            if (visited[m]) continue;
            const float d = std::fabs(dot(normals[v], normals[m]));
            if (!heap.contains(m) || d > heap.key(m)) {
                heap.push_or_raise(m, d);
                parent[m] = v;
            }
        }
    };
    // Prim: pops the unvisited point with the best edge to the visited set, orients it like the
    // end of that edge.
    auto drain = [&](std::uint32_t seed) {
        while (!heap.empty()) {
            const std::uint32_t v = heap.pop();
            const float w = heap.key(v);  // the best |n_p . n_v| over v's visited neighbours
            visited[v] = 1;
            if (component) (*component)[v] = static_cast<std::uint32_t>(stats.components);
            if (v != seed) {
                if (dot(normals[parent[v]], normals[v]) < 0.f) {
                    flip(normals[v]);
                    if (fixed) ++stats.flipped;
                }
                if (w < k_ambiguous_dot) ++stats.ambiguous;
            }
            push_neighbours(v);
            if ((++done & 0xFFFF) == 0) progress.update(done);
        }
    };

    if (fixed) {
        for (std::size_t i = 0; i < n; ++i)
            if (ok[i] && (*fixed)[i]) {
                visited[i] = 1;
                ++done;
            }
        for (std::size_t i = 0; i < n; ++i)
            if (ok[i] && (*fixed)[i]) push_neighbours(static_cast<std::uint32_t>(i));
        drain(k_no_neighbour);
    }

    // Seeds: the unvisited point with the largest z is the top of its (wholly unvisited) component.
    std::vector<std::uint32_t> by_height;
    by_height.reserve(n);
    for (std::size_t i = 0; i < n; ++i)
        if (ok[i] && !visited[i]) by_height.push_back(static_cast<std::uint32_t>(i));
    std::sort(by_height.begin(), by_height.end(), [&](std::uint32_t a, std::uint32_t b) {
        return positions[a][2] > positions[b][2] || (positions[a][2] == positions[b][2] && a < b);
    });
    for (const std::uint32_t seed : by_height) {
        if (visited[seed]) continue;
        ++stats.components;
        if (normals[seed].z < 0.f) flip(normals[seed]);
        if (std::fabs(normals[seed].z) < k_ambiguous_dot) ++stats.ambiguous;
        heap.push_or_raise(seed, 2.f);  // above any |dot|: popped first
        drain(seed);
    }
    progress.finish();
    return stats;
}

OrientStats orient_toward(const std::vector<std::array<double, 3>>& positions,
                          std::vector<pool::Float3>& normals, const std::vector<pool::Sensor>& sensors,
                          const std::vector<std::uint16_t>& scan_ids, std::vector<std::uint8_t>* ambiguous,
                          const std::vector<std::uint8_t>* only) {
    OrientStats stats;
    if (ambiguous) ambiguous->assign(normals.size(), 0);
    for (std::size_t i = 0; i < normals.size(); ++i) {
        if (only && !(*only)[i]) continue;
        const int r =
            orient_toward_one(positions[i], normals[i], sensors[scan_ids.empty() ? 0 : scan_ids[i]]);
        if (r == 2) {
            ++stats.skipped;
        } else if (r == 1) {
            ++stats.ambiguous;
            if (ambiguous) (*ambiguous)[i] = 1;
        }
    }
    return stats;
}

OrientStats orient_toward(const std::vector<std::array<double, 3>>& positions,
                          std::vector<pool::Float3>& normals, const std::array<double, 3>& sensor) {
    const std::vector<pool::Sensor> sensors{
        pool::Sensor{{sensor[0], sensor[1], sensor[2]}, pool::k_sensor_point, 0}};
    return orient_toward(positions, normals, sensors, {});
}

}  // namespace prt::pre::import
