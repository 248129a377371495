// PointRT pool file: the Implicit Surface Octree sections (types 32-35, written by prt-iso, thesis
// ch. 4). Plain structs only: this header compiles under g++ and nvcc, and the core
// (prt/core/iso.h) reads the mapped section payloads through these structs without conversion.
//
// An ISO is an octree whose filled leaves each hold a small surface patch: the values of the
// implicit function f(Q) = (Q - p(Q)) . n(Q) (thesis 4.2, eq. 4.1-4.3) at the leaf's 8 corners,
// with the weighted normals and colors there; inside the leaf f, the normal and the color are
// trilinear interpolations of the corner values (thesis 4.3) and the surface is f = 0.
//
//   iso_info (32)        one IsoInfo (64 B): root cube, counts, levels, build parameters, flags
//   iso_nodes (33)       uint32 node words, the splat octree's encoding (pool_layout.h):
//                          bits 31..30 type (0 internal, 1 filled leaf, 2 empty leaf)
//                          bits 29..0  internal: index of the first of 8 children (Morton order
//                                      c = x | y << 1 | z << 2, a 1 = upper half on that axis);
//                                      filled leaf: index into the leaf arrays below; empty: 0
//                        node 0 is the root, nodes breadth first (every child after its parent)
//   iso_leaves_q8 (34)   IsoLeafQ8[leaf_count] (56 B, thesis 4.4: one byte per component)
//   iso_leaves_f32 (35)  IsoLeafF32[leaf_count] (160 B, full precision)
//                        a pool holds one or both leaf arrays (IsoFlags), same leaf order:
//                        filled leaves in depth-first (Morton) order of the tree
//
// Corners of a leaf are numbered like children: corner c = x | y << 1 | z << 2 sits at
// cell_min + (x, y, z) * edge. A leaf at level l with integer cell coordinates (i, j, k) spans
// root_min + root_size * [i, i + 1] x [j, j + 1] x [k, k + 1] / 2^l (local frame).
//
//   IsoLeafQ8 (56 bytes)
//   +0   int8  value[8]       corner isovalues, sign preserved: f > 0 -> 1..127, f <= 0 -> -127..0;
//                             f = value / 127 * k_iso_q8_range * edge(level), clamped
//   +8   int8  normal[8][3]   unit normal per corner, component = value / 127
//   +32  uint8 color[8][3]    sRGB color per corner (255 everywhere when the model has none)
//
//   IsoLeafF32 (160 bytes)
//   +0   float value[8]       corner isovalues, local-frame units
//   +32  float normal[8][3]   unit normal per corner
//   +128 Rgba8 color[8]       sRGB color per corner (alpha 255)
//
// Corners are replicated in every leaf, as in thesis 4.4, not shared through indices: measured on
// prt-synth's 1M-point sphere (scripts/bench-iso.sh), leaves have 2.3 distinct corners each, so
// sharing would store 8 x 4-byte indices + 2.3 x 7 bytes = 48 bytes per leaf instead of 56 (14%
// less), for 8 scattered reads per leaf instead of one 56-byte record, and a corner shared by
// leaves of two levels could not use the leaf-relative quantization scale. Not adopted.
#pragma once

#include <cstddef>
#include <cstdint>

#include "prt/formats/pool_layout.h"

namespace prt::pool {

/// Deepest leaf level prt-iso builds and a valid pool holds (root = 0). Corner coordinates at this
/// level take 21 bits per axis (63-bit Morton keys in the builder); float positions carry no more.
inline constexpr std::uint32_t k_max_iso_level = 20;
/// Range of the quantized isovalues, in leaf edges: |f| up to 2 edges is represented, larger values
/// are clamped (only corners far from the leaf's surface get there; their sign is kept).
inline constexpr float k_iso_q8_range = 2.0f;

/// ISO-wide facts (section iso_info, exactly one element).
struct IsoInfo {
    float root_min[3];             ///< 0: root cube corner, local frame
    float root_size;               ///< 12: root cube edge (> 0)
    std::uint32_t node_count;      ///< 16: elements of iso_nodes
    std::uint32_t leaf_count;      ///< 20: filled leaves = elements of each leaf array present
    std::uint32_t min_level;       ///< 24: the build's minimum leaf level (thesis 4.6)
    std::uint32_t max_level;       ///< 28: the build's maximum leaf level (<= k_max_iso_level)
    std::uint32_t depth;           ///< 32: deepest filled leaf level
    std::uint32_t flags;           ///< 36: IsoFlags
    float smoothing;               ///< 40: Gaussian sigma_i = smoothing x radius of influence r_i
    float support;                 ///< 44: points count at a corner within support x sigma_i
    std::uint32_t active_leaves;   ///< 48: filled leaves holding a point (thesis 4.3.1)
    std::uint32_t passive_leaves;  ///< 52: filled leaves holding none, inside a point's influence
    std::uint32_t corner_count;    ///< 56: distinct corners evaluated (informative)
    std::uint32_t reserved;        ///< 60: 0
};
static_assert(sizeof(IsoInfo) == 64);
static_assert(offsetof(IsoInfo, root_size) == 12);
static_assert(offsetof(IsoInfo, node_count) == 16);
static_assert(offsetof(IsoInfo, flags) == 36);
static_assert(offsetof(IsoInfo, smoothing) == 40);
static_assert(offsetof(IsoInfo, active_leaves) == 48);
static_assert(offsetof(IsoInfo, reserved) == 60);

/// IsoInfo::flags bits.
enum IsoFlags : std::uint32_t {
    k_iso_has_q8 = 1u << 0,     ///< iso_leaves_q8 present
    k_iso_has_f32 = 1u << 1,    ///< iso_leaves_f32 present
    k_iso_colors = 1u << 2,     ///< corner colors come from the model's colors (else 255)
    k_iso_balanced = 1u << 3,   ///< thesis 4.5.1: filled leaves sharing a face, edge or corner
                                ///<   differ by at most one level
    k_iso_radii_knn = 1u << 4,  ///< radii of influence from prt-iso's own k-NN, not the radii section
};

/// One filled leaf, quantized (56 bytes, thesis 4.4).
struct IsoLeafQ8 {
    std::int8_t value[8];      ///< 0: corner isovalues (sign-preserving, see the header comment)
    std::int8_t normal[8][3];  ///< 8: corner unit normals x 127
    std::uint8_t color[8][3];  ///< 32: corner sRGB colors
};
static_assert(sizeof(IsoLeafQ8) == 56);
static_assert(offsetof(IsoLeafQ8, normal) == 8);
static_assert(offsetof(IsoLeafQ8, color) == 32);

/// One filled leaf, full precision (160 bytes).
struct IsoLeafF32 {
    float value[8];      ///< 0: corner isovalues, local-frame units
    float normal[8][3];  ///< 32: corner unit normals
    Rgba8 color[8];      ///< 128: corner sRGB colors
};
static_assert(sizeof(IsoLeafF32) == 160);
static_assert(offsetof(IsoLeafF32, normal) == 32);
static_assert(offsetof(IsoLeafF32, color) == 128);

}  // namespace prt::pool
