// PointRT: the patch sections of a pool (types 112-115, formats/POOL.md "Bezier patches") read back
// validated: formats' validate_patches (prt/formats/patch_sections.h), named here for prt-patches and
// its tests. Writing them is write_patch_sections (patch_build.h); the core view of a pool's patches
// is the runtime's load_patch_view (prt/runtime/surface_pools.h).
#pragma once

#include "prt/formats/patch_sections.h"

namespace prt::patches {

using pool::has_patches;
using pool::validate_patches;

}  // namespace prt::patches
