// PointRT: the MLS sections of a pool (types 48-53, formats/POOL.md "MLS surface"): writing them;
// reading them back validated is formats' validate_mls (prt/formats/mls_sections.h), and the core
// view of a pool's MLS surface the runtime's load_mls_view (prt/runtime/surface_pools.h).
#pragma once

#include "mls_build.h"
#include "prt/core/mls.h"
#include "prt/formats/mls_sections.h"
#include "prt/formats/pool.h"

namespace prt::mls {

/// Reading the sections back validated (formats).
using pool::has_mls;
using pool::validate_mls;

/// Adds (replacing) mls_info, mls_nodes, mls_refs and mls_splats to `writer`, and the BVH sections
/// when the model has a BVH (else removes an earlier one), taking the arrays.
void write_mls_sections(MlsModel&& model, pool::PoolWriter& writer);

/// The view of a freshly built model in memory (tests, benchmarks); valid while `model` lives.
core::MlsView make_view(const MlsModel& model);

}  // namespace prt::mls
