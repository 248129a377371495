// PointRT: the ISO sections of a pool (types 32-35, formats/POOL.md "Implicit Surface Octree"):
// writing them; reading them back validated is formats' validate_iso (prt/formats/iso_sections.h),
// and the core view of a pool's ISO the runtime's load_iso_view (prt/runtime/surface_pools.h).
#pragma once

#include "iso_build.h"
#include "prt/core/iso.h"
#include "prt/formats/iso_sections.h"
#include "prt/formats/pool.h"

namespace prt::iso {

/// Reading the sections back validated (formats).
using pool::has_iso;
using pool::validate_iso;

/// Adds (replacing) iso_info, iso_nodes and the leaf arrays the model has to `writer` (a leaf array
/// the model lacks is removed, so a carried-over stale one cannot survive), taking the arrays.
void write_iso_sections(IsoModel&& model, pool::PoolWriter& writer);

/// The view of a freshly built model in memory (tests, benchmarks); valid while `model` lives.
core::IsoView make_view(const IsoModel& model, bool prefer_q8 = true);

}  // namespace prt::iso
