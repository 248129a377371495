// PointRT pool file: the Implicit Surface Octree sections (types 32-35, iso_layout.h, written by
// prt-iso) of an opened pool, validated into typed views (formats/POOL.md, "Implicit Surface
// Octree"). The runtime builds the core's IsoView from them (prt::rt::load_iso_view). Host only.
#pragma once

#include <cstdint>
#include <span>

#include "prt/formats/iso_layout.h"
#include "prt/formats/pool.h"

namespace prt::pool {

/// The ISO sections of a pool, validated: views into the mapped file, valid while the PoolFile lives.
struct IsoSections {
    IsoInfo info{};
    std::span<const std::uint32_t> nodes;    ///< info.node_count node words, node 0 the root
    std::span<const IsoLeafQ8> leaves_q8;    ///< info.leaf_count leaves; data() null when absent
    std::span<const IsoLeafF32> leaves_f32;  ///< info.leaf_count leaves; data() null when absent
};

/// Whether the pool holds any of the ISO sections (32-35).
bool has_iso(const PoolFile& pool);

/// Validates the ISO sections: iso_info and iso_nodes present, exactly one IsoInfo, the leaf arrays
/// IsoInfo's flags name present with leaf_count elements and no others, root cube finite with a
/// positive edge, levels within k_max_iso_level, the nodes a proper tree from node 0 (every child
/// group after its parent and reached once, no internal node at max_level), depth as recorded,
/// every filled leaf addressing a distinct leaf in range and every leaf addressed, float values and
/// normals finite. Throws prt::Error "FILE: section NAME: what is wrong" on the first problem.
IsoSections validate_iso(const PoolFile& pool);

}  // namespace prt::pool
