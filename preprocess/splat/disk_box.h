// PointRT preprocess: the exact disk/box overlap test (thesis 3.4), shared with the CUDA octree
// builder and so defined in the core (prt/core/disk_box.h, with its derivation); these names are
// the preprocessors' (prt-iso, the splat octree builder).
#pragma once

#include "prt/core/disk_box.h"

namespace prt::pre {

using core::disk_half_extent;
using core::disk_overlaps_box;
using core::plane_box_distance_sq;

}  // namespace prt::pre
