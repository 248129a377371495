// PointRT core: 3D Morton (Z-order) codes, the one interleaving every builder uses, host and device
// (prt-radii's query order on either backend, the octree builders' splat order, prt-mls's point
// order, prt-iso's point and corner codes, the GI octrees of prt-photons and prt-lightmap;
// preprocess/common/morton.h gives them to the tools).
//
// 21 bits per axis, x lowest: bit k of x goes to bit 3k, of y to 3k + 1, of z to 3k + 2, so the
// triplet of one level is the octree's child index c = x | y << 1 | z << 2 (pool_layout.h).
// Morton 1966, "A computer oriented geodetic data base and a new technique in file sequencing";
// the spreading by shifts and masks is the usual "magic bits" form.
#pragma once

#include <cstdint>

#include "prt/core/config.h"

namespace prt::core {

/// Largest coordinate a code holds per axis (21 bits).
inline constexpr std::uint32_t k_morton_max = (1u << 21) - 1;

/// Spreads the low 21 bits of v to every third bit (bit k -> bit 3k).
PRT_HD PRT_INLINE std::uint64_t spread_bits21(std::uint64_t v) {
    v &= 0x1fffffull;
    v = (v | (v << 32)) & 0x1f00000000ffffull;
    v = (v | (v << 16)) & 0x1f0000ff0000ffull;
    v = (v | (v << 8)) & 0x100f00f00f00f00full;
    v = (v | (v << 4)) & 0x10c30c30c30c30c3ull;
    v = (v | (v << 2)) & 0x1249249249249249ull;
    return v;
}

/// Inverse of spread_bits21: every third bit of v (starting at bit 0) packed into 21 bits.
PRT_HD PRT_INLINE std::uint32_t compact_bits21(std::uint64_t v) {
    v &= 0x1249249249249249ull;
    v = (v | (v >> 2)) & 0x10c30c30c30c30c3ull;
    v = (v | (v >> 4)) & 0x100f00f00f00f00full;
    v = (v | (v >> 8)) & 0x1f0000ff0000ffull;
    v = (v | (v >> 16)) & 0x1f00000000ffffull;
    v = (v | (v >> 32)) & 0x1fffffull;
    return static_cast<std::uint32_t>(v);
}

/// The code of cell (x, y, z), each below 2^21.
PRT_HD PRT_INLINE std::uint64_t morton3(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    return spread_bits21(x) | (spread_bits21(y) << 1) | (spread_bits21(z) << 2);
}

/// The cell of a code (inverse of morton3).
PRT_HD PRT_INLINE void demorton3(std::uint64_t code, std::uint32_t& x, std::uint32_t& y, std::uint32_t& z) {
    x = compact_bits21(code);
    y = compact_bits21(code >> 1);
    z = compact_bits21(code >> 2);
}

}  // namespace prt::core
