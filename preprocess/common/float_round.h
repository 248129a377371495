// PointRT preprocess: doubles rounded to float outwards, for boxes that must still enclose their
// double-precision contents once stored as floats (octree, MLS and patch bounds): runtime/core's
// (prt/core/float_round.h, shared with the CUDA octree builder's disk boxes).
#pragma once

#include "prt/core/float_round.h"

namespace prt::pre {

using core::next_float_down;
using core::next_float_up;
using core::round_down;
using core::round_up;

}  // namespace prt::pre
