// PointRT: the patch sections of a pool read back validated as the core's PatchView. The
// validation lives with the renderer that depends on it (runtime/host, prt/runtime/surface_pools.h);
// prt-patches and its tests use the same functions under these names.
#pragma once

#include "prt/runtime/surface_pools.h"

namespace prt::patches {

using rt::has_patches;
using rt::load_patch_view;

}  // namespace prt::patches
