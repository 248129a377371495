// PointRT: the ISO sections of a pool (types 32-35, formats/POOL.md "Implicit Surface Octree"):
// writing them, and reading them back validated as the core's IsoView (host pointers into the
// mapped file). Every cross-reference the traversal relies on is checked here, so a bad pool gives
// a one-line error instead of a crash, an endless loop or a garbage image.
#pragma once

#include "iso_build.h"
#include "prt/core/iso.h"
#include "prt/formats/pool.h"

namespace prt::iso {

/// Whether the pool holds any of the ISO sections.
bool has_iso(const pool::PoolFile& pool);

/// Adds (replacing) iso_info, iso_nodes and the leaf arrays the model has to `writer` (a leaf array
/// the model lacks is removed, so a carried-over stale one cannot survive), taking the arrays.
void write_iso_sections(IsoModel&& model, pool::PoolWriter& writer);

/// Validates the ISO sections (iso_info and iso_nodes present, exactly one IsoInfo, the leaf arrays
/// IsoInfo's flags name present with leaf_count elements and no others, root cube finite with a
/// positive edge, levels within pool::k_max_iso_level, the nodes a proper tree from node 0 with
/// every child group after its parent and reached once, depth as recorded, every filled leaf
/// addressing a distinct leaf in range and every leaf addressed, float values and normals finite)
/// and returns the view (quantized leaves preferred when `prefer_q8` and present). Throws
/// prt::Error "FILE: section NAME: what is wrong" otherwise.
core::IsoView load_iso_view(const pool::PoolFile& pool, bool prefer_q8 = true);

/// The view of a freshly built model in memory (tests, benchmarks); valid while `model` lives.
core::IsoView make_view(const IsoModel& model, bool prefer_q8 = true);

}  // namespace prt::iso
