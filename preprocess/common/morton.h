// PointRT preprocess: 3D Morton (Z-order) codes for the tools: runtime/core's (prt/core/morton.h,
// shared with the CUDA builders, which must order points exactly as the CPU does).
#pragma once

#include "prt/core/morton.h"

namespace prt::pre {

using core::compact_bits21;
using core::demorton3;
using core::k_morton_max;
using core::morton3;
using core::spread_bits21;

}  // namespace prt::pre
