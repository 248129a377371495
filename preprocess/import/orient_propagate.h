// PointRT prt-import: the multi-source Prim of orient_by_propagation() (orient.h) over a graph given
// as adjacency lists, shared by the in-core orientation (the whole k-NN graph) and the out-of-core
// import (the part of the graph around the grazing normals, out_of_core.cpp), so both take the
// same steps in the same order and give the same signs.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "orient.h"
#include "progress.h"

namespace prt::pre::import {

namespace orient_detail {

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
/// at most one entry per point, so memory stays O(n) however dense the graph is. Its arrays are
/// given (n each; `pos` all -1, `key` all 0 at the start): vectors in core, spill files out of core.
class IndexedMaxHeap {
public:
    IndexedMaxHeap(std::span<std::int64_t> pos, std::span<float> key, std::span<std::uint32_t> heap)
        : m_pos(pos), m_key(key), m_heap(heap) {}
    bool empty() const { return m_size == 0; }
    bool contains(std::uint32_t v) const { return m_pos[v] >= 0; }
    float key(std::uint32_t v) const { return m_key[v]; }
    void push_or_raise(std::uint32_t v, float key) {
        if (m_pos[v] < 0) {
            m_key[v] = key;
            m_pos[v] = static_cast<std::int64_t>(m_size);
            m_heap[m_size++] = v;
            up(m_size - 1);
        } else if (key > m_key[v]) {
            m_key[v] = key;
            up(static_cast<std::size_t>(m_pos[v]));
        }
    }
    std::uint32_t pop() {
        const std::uint32_t top = m_heap[0];
        m_pos[top] = -1;
        const std::uint32_t last = m_heap[--m_size];
        if (m_size > 0) {
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
        const std::size_t n = m_size;
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

    std::span<std::int64_t> m_pos;
    std::span<float> m_key;
    std::span<std::uint32_t> m_heap;
    std::size_t m_size = 0;
};

}  // namespace orient_detail

/// orient_by_propagation()'s propagation over the vertices 0 .. n-1 of a graph: vertex v's
/// neighbours are adjacent[begin[v] .. begin[v + 1]) (in that order: it decides ties); `ok` (may
/// be null: all) marks the vertices with a valid normal (the others take no part and have no
/// edges), `fixed` (may be null) the sources, height(v) orders the seeds of the components no
/// source reaches (largest first, then the lower vertex number). Counts add to `stats`.
/// `workspace` (may be null: vectors) holds the per-vertex arrays (out of core: spill files).
/// The per-vertex arrays of propagate_signs() (n each), and what to call every 4096 vertices
/// (out of core: drop the spill files' pages; the propagation reads them at random).
struct PropagationWorkspace {
    std::span<std::uint8_t> visited;
    std::span<std::uint32_t> parent;
    std::span<std::int64_t> pos;
    std::span<float> key;
    std::span<std::uint32_t> heap;
    std::span<std::uint32_t> order;
    std::function<void()> tick;
};

template <class Height>
OrientStats propagate_signs(std::size_t n, std::span<const std::uint64_t> begin,
                            std::span<const std::uint32_t> adjacent, std::span<pool::Float3> normals,
                            const std::uint8_t* ok, const std::uint8_t* fixed, Height&& height, bool quiet,
                            std::vector<std::uint32_t>* component, OrientStats stats = {},
                            const PropagationWorkspace* workspace = nullptr) {
    using namespace orient_detail;
    std::vector<std::uint8_t> visited_v;
    std::vector<std::uint32_t> parent_v, heap_v, order_v;
    std::vector<std::int64_t> pos_v;
    std::vector<float> key_v;
    PropagationWorkspace ws;
    if (workspace) {
        ws = *workspace;
    } else {
        visited_v.resize(n);
        parent_v.resize(n);
        heap_v.resize(n);
        order_v.resize(n);
        pos_v.resize(n);
        key_v.resize(n);
        ws = {visited_v, parent_v, pos_v, key_v, heap_v, order_v, {}};
    }
    const std::span<std::uint8_t> visited = ws.visited;
    const std::span<std::uint32_t> parent = ws.parent;
    for (std::size_t i = 0; i < n; ++i) {
        visited[i] = ok ? !ok[i] : 0;
        parent[i] = k_no_neighbour;
        ws.pos[i] = -1;
        ws.key[i] = 0.f;
    }
    if (component) component->assign(n, 0);
    IndexedMaxHeap heap(ws.pos, ws.key, ws.heap);
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
            if (ws.tick && (done & 0xFFF) == 0) ws.tick();
        }
    };

    if (fixed) {
        for (std::size_t i = 0; i < n; ++i)
            if (fixed[i]) {
                visited[i] = 1;
                ++done;
            }
        for (std::size_t i = 0; i < n; ++i)
            if (fixed[i]) push_neighbours(static_cast<std::uint32_t>(i));
        drain(k_no_neighbour);
    }

    // Seeds: the unvisited point with the largest z is the top of its (wholly unvisited) component.
    std::size_t unvisited = 0;
    for (std::size_t i = 0; i < n; ++i)
        if (!visited[i]) ws.order[unvisited++] = static_cast<std::uint32_t>(i);
    const std::span<std::uint32_t> by_height = ws.order.subspan(0, unvisited);
    std::sort(by_height.begin(), by_height.end(), [&](std::uint32_t a, std::uint32_t b) {
        return height(a) > height(b) || (height(a) == height(b) && a < b);
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

}  // namespace prt::pre::import
