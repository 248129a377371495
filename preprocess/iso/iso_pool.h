// PointRT: the ISO sections of a pool (types 32-35, formats/POOL.md "Implicit Surface Octree"):
// writing them; reading them back validated is the runtime's load_iso_view (surface_pools.h).
#pragma once

#include "iso_build.h"
#include "prt/core/iso.h"
#include "prt/formats/pool.h"
#include "prt/runtime/surface_pools.h"

namespace prt::iso {

/// Reading the sections back validated: the runtime's functions (prt/runtime/surface_pools.h).
using rt::has_iso;
using rt::load_iso_view;

/// Adds (replacing) iso_info, iso_nodes and the leaf arrays the model has to `writer` (a leaf array
/// the model lacks is removed, so a carried-over stale one cannot survive), taking the arrays.
void write_iso_sections(IsoModel&& model, pool::PoolWriter& writer);

/// The view of a freshly built model in memory (tests, benchmarks); valid while `model` lives.
core::IsoView make_view(const IsoModel& model, bool prefer_q8 = true);

}  // namespace prt::iso
