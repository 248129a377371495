// PointRT: the MLS sections of a pool (types 48-51, formats/POOL.md "MLS surface"): writing them,
// and reading them back validated as the core's MlsView (host pointers into the mapped file).
// Every cross-reference the traversal relies on is checked here, so a bad pool gives a one-line
// error instead of a crash or an endless loop.
#pragma once

#include "mls_build.h"
#include "prt/core/mls.h"
#include "prt/formats/pool.h"

namespace prt::mls {

/// Whether the pool holds any of the MLS sections.
bool has_mls(const pool::PoolFile& pool);

/// Adds (replacing) mls_info, mls_nodes, mls_refs and mls_splats to `writer`, taking the arrays.
void write_mls_sections(MlsModel&& model, pool::PoolWriter& writer);

/// Validates the four MLS sections (all present, exactly one MlsInfo, counts agreeing, finite
/// values, supports > 0, point indices below ModelInfo::point_count, refs in range, the nodes a
/// proper tree from node 0 with children after their parent, every node reached once, split
/// planes inside their cell, leaves covering mls_refs exactly once, depth as recorded and at most
/// pool::k_max_mls_depth) and returns the view. Throws prt::Error "FILE: section NAME: what is
/// wrong" otherwise.
core::MlsView load_mls_view(const pool::PoolFile& pool);

/// The view of a freshly built model in memory (tests, benchmarks); valid while `model` lives.
core::MlsView make_view(const MlsModel& model);

}  // namespace prt::mls
