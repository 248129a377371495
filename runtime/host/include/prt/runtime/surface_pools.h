// PointRT runtime (host): the ISO, MLS and patch sections of a pool as the core's views (host
// pointers into the mapped file; the CUDA backend copies the same bytes to the GPU). The sections
// are validated by formats (prt/formats/iso_sections.h, mls_sections.h, patch_sections.h: every
// cross-reference a traversal relies on); each load_* throws prt::Error "FILE: section NAME: what
// is wrong" on a bad pool.
#pragma once

#include "prt/core/iso.h"
#include "prt/core/mls.h"
#include "prt/core/patch.h"
#include "prt/formats/iso_sections.h"
#include "prt/formats/mls_sections.h"
#include "prt/formats/patch_sections.h"
#include "prt/formats/pool.h"

namespace prt::rt {

/// Whether the pool holds any of the ISO (32-35), MLS (48-53), patch (112-115) sections.
using pool::has_iso;
using pool::has_mls;
using pool::has_patches;

/// The ISO sections validated (pool::validate_iso) as the core's view, the quantized leaves traced
/// when `prefer_q8` and present.
core::IsoView load_iso_view(const pool::PoolFile& pool, bool prefer_q8 = true);

/// The four MLS sections validated (pool::validate_mls) as the core's view.
core::MlsView load_mls_view(const pool::PoolFile& pool);

/// The four patch sections validated (pool::validate_patches) as the core's view.
core::PatchView load_patch_view(const pool::PoolFile& pool);

}  // namespace prt::rt
