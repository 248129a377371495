// PointRT prt-import: exact k nearest neighbours over a point set, the one neighbour search of the
// import (outlier removal, PCA normals, orientation graph). Our own code, so every build (with or
// without PCL / FLANN) finds the same neighbours and removes the same outliers.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace prt::pre::import {

/// A kd-tree over a fixed point set (Friedman, Bentley & Finkel 1977, "An algorithm for finding
/// best matches in logarithmic expected time", ACM TOMS 3(3)): median splits along the widest
/// extent of each cell, buckets of at most k_bucket points. Points are stored as float offsets from
/// the bounding-box centre (a scan far from the origin keeps float precision relative to its size),
/// reordered leaf after leaf so a bucket is contiguous in memory. The shape of the tree follows from
/// the point count alone (each node halves its range), so nodes need no pointers. Searches carry the
/// squared distance to the current cell incrementally (Arya & Mount 1993, "Algorithms for fast
/// vector quantization"), nearer child first.
class KdTree {
public:
    static constexpr std::uint32_t k_bucket = 12;

    /// Builds over `positions` (finite); `threads` 0 = every hardware thread.
    explicit KdTree(const std::vector<std::array<double, 3>>& positions, unsigned threads = 0);

    std::size_t size() const { return m_points.size(); }

    /// The (up to) k points nearest to point `self` other than itself, skipping points i with
    /// `excluded[i]` set (when not null): their indices into the original positions in `index` and
    /// their squared distances in `distance2`, nearest first (ties: smaller index first). Returns how
    /// many were found (< k only when the set has fewer eligible points).
    std::uint32_t nearest(std::uint32_t self, std::uint32_t k, const std::uint8_t* excluded,
                          std::uint32_t* index, float* distance2) const;

    /// Calls `visit(i, index, distance2, found)` for every point i with its k nearest other points
    /// (as nearest()), in parallel over `threads` workers (0 = all), in the tree's order (queries
    /// near each other in space run one after another, which keeps the tree in cache). `visit` must
    /// be safe to call concurrently for different points; `progress(done)` is called from one
    /// worker.
    void for_each(
        std::uint32_t k, unsigned threads,
        const std::function<void(std::uint32_t, const std::uint32_t*, const float*, std::uint32_t)>& visit,
        const std::function<void(std::uint64_t)>& progress = {}) const;

private:
    struct Point {
        float x, y, z;
        std::uint32_t index;  ///< into the original positions
    };
    void build(std::size_t node, std::size_t begin, std::size_t end, unsigned depth, unsigned spawn);
    void descend(const void* query, std::size_t node, std::size_t begin, std::size_t end, unsigned depth,
                 float rd, float* off) const;
    std::uint32_t search(const float q[3], std::uint32_t self, std::uint32_t k, const std::uint8_t* excluded,
                         std::uint32_t* index, float* distance2) const;

    std::vector<Point> m_points;  ///< leaf order
    std::vector<float> m_split;   ///< per internal node (heap order: children 2i+1, 2i+2)
    std::vector<std::uint8_t> m_axis;
    std::vector<std::uint32_t> m_slot;  ///< original index -> position in m_points
    unsigned m_depth = 0;               ///< internal levels; nodes at this depth are buckets
};

}  // namespace prt::pre::import
