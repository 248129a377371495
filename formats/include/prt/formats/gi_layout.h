// PointRT pool file: the global-illumination sections: the caustic octree (types 64-66, written by
// prt-photons, thesis 5.4) and the diffuse light map (types 80-82, written by prt-lightmap, thesis
// 5.3). Plain structs only: this header compiles under g++ and nvcc, and the core (prt/core/gi.h)
// reads the mapped section payloads through these structs without conversion.
//
// Both are sparse octrees whose filled leaves all sit at one level (GiInfo::depth) and hold an RGB
// value at each of their 8 corners; a lookup descends to the leaf holding the point and
// interpolates the corners trilinearly (thesis 5.4.2). The octree's root cube is the model's splat
// octree root (local frame, ModelInfo::origin), so the map travels with the pool.
//
//   caustic_info (64)     one GiInfo per map: root cube, depth, counts, gather radius, scale,
//                         placement (issue 20: a pool placed several times holds one map per
//                         placement; the maps' nodes and leaves follow one another in this order)
//   caustic_nodes (65)    uint32 node words, the splat octree's encoding (pool_layout.h):
//                           bits 31..30 type (0 internal, 1 filled leaf, 2 empty leaf)
//                           bits 29..0  internal: index of the first of 8 children (Morton order
//                                       c = x | y << 1 | z << 2, a 1 = upper half on that axis);
//                                       filled leaf: index into caustic_leaves; empty: 0
//                         node 0 is the root, nodes breadth first (every child after its parent);
//                         every filled leaf is at level depth
//   caustic_leaves (66)   GiLeaf per filled leaf: corner irradiance (thesis eq. 5.1-5.2 density
//                         estimate of the deposited photon flux), local-frame units
//   light_map_info (80), light_map_nodes (81), light_map_leaves (82): the same layout, one map per
//                         placement too; corner values are indirect irradiance (thesis eq. 5.3-5.4 weighted
//                         average of the path-traced samples)
//
// Corners of a leaf are numbered like children: corner c = x | y << 1 | z << 2 sits at
// cell_min + (x, y, z) * edge; a leaf with integer cell coordinates (i, j, k) spans
// root_min + root_size * [i, i + 1] x [j, j + 1] x [k, k + 1] / 2^depth.
//
//   GiLeaf (36 bytes)
//   +0   uint32 corner[8]   RGB9E5 (shared exponent: 9-bit mantissas, 5-bit exponent, bias 15) of
//                           value / GiInfo::scale; decoded value = rgb9e5 x scale
//   +32  int8   normal[3]   the leaf's surface normal x 127 (the side the values belong to), or
//                           (0, 0, 0) when the samples came from both sides: no test
//   +35  uint8  reserved    0
//
// RGB9E5 keeps 9 significant bits per channel relative to the largest channel (0.2 % steps) in a
// quarter of the float size: a leaf is 36 bytes instead of 104 with float RGB.
#pragma once

#include <cstddef>
#include <cstdint>

#include "prt/formats/pool_layout.h"

namespace prt::pool {

/// Deepest leaf level of a caustic or light-map octree (corner keys then take 21 bits per axis).
inline constexpr std::uint32_t k_max_gi_depth = 20;

/// Caustic / light-map facts (sections caustic_info and light_map_info: one element per map, one
/// map per placement of the pool).
struct GiInfo {
    float root_min[3];           ///< 0: root cube corner, local frame
    float root_size;             ///< 12: root cube edge (> 0)
    std::uint32_t depth;         ///< 16: level of every filled leaf (<= k_max_gi_depth)
    std::uint32_t node_count;    ///< 20: elements of the nodes section
    std::uint32_t leaf_count;    ///< 24: elements of the leaves section
    std::uint32_t flags;         ///< 28: reserved, 0
    float gather_radius;         ///< 32: local units: the footprint g of eq. 5.1-5.4
    float scale;                 ///< 36: decoded corner value = RGB9E5 value x scale (> 0)
    float cos_threshold;         ///< 40: a lookup whose normal n has dot(n, leaf normal) below this
                                 ///<     finds nothing (leaves with a zero normal accept every n)
    std::uint32_t placement;     ///< 44: the scene placement this map belongs to
                                 ///<     (pool::placement_key), 0: any placement
    std::uint64_t sample_count;  ///< 48: photons deposited (caustics) or samples traced (light map)
    float total[2];              ///< 56: caustics: deposited flux (luminance) and emitted flux of
                                 ///<     all lights; light map: mean and max corner luminance
};
static_assert(sizeof(GiInfo) == 64);
static_assert(offsetof(GiInfo, depth) == 16);
static_assert(offsetof(GiInfo, gather_radius) == 32);
static_assert(offsetof(GiInfo, cos_threshold) == 40);
static_assert(offsetof(GiInfo, sample_count) == 48);
static_assert(offsetof(GiInfo, total) == 56);

/// One filled leaf (36 bytes): 8 RGB9E5 corner values and the leaf's normal.
struct GiLeaf {
    std::uint32_t corner[8];  ///< 0: RGB9E5 corner values (x GiInfo::scale)
    std::int8_t normal[3];    ///< 32: unit normal x 127, or zero
    std::uint8_t reserved;    ///< 35: 0
};
static_assert(sizeof(GiLeaf) == 36);
static_assert(offsetof(GiLeaf, normal) == 32);

}  // namespace prt::pool
