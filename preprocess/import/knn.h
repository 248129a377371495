// PointRT prt-import: exact k nearest neighbours over a point set, the one neighbour search of the
// import (outlier removal, PCA normals, orientation graph): the shared kd-tree (kd_tree.h), so every
// build (with or without PCL) finds the same neighbours and removes the same outliers.
#pragma once

#include <array>
#include <vector>

#include "kd_tree.h"

namespace prt::pre::import {

/// The shared kd-tree over float offsets from the bounding-box centre (a scan far from the origin
/// keeps float precision relative to its size).
class KdTree : public pre::KdTree<float> {
public:
    /// Builds over `positions` (finite); `threads` 0 = every hardware thread.
    explicit KdTree(const std::vector<std::array<double, 3>>& positions, unsigned threads = 0);
};

}  // namespace prt::pre::import
