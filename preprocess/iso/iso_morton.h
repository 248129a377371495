// PointRT preprocess (prt-iso internals): Morton codes at the deepest ISO level and range queries
// over points sorted by them. Host only.
//
// Every point gets the Morton code (morton.h) of its cell at level K = pool::k_max_iso_level (20) of
// the root cube: 3 x 20 interleaved bits, x lowest (bit 3k = x bit k, 3k + 1 = y, 3k + 2 = z), so the
// triplet at bits 3 (K - l - 1) .. 3 (K - l) - 1 is the child octant c = x | y << 1 | z << 2 taken at
// level l, exactly the octree's child order. Sorted by code, the points of any octree node form
// one contiguous range, found by two binary searches on the node's code prefix. Corners use the
// same interleaving over 21 bits per axis (coordinates 0..2^K inclusive).
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <span>

#include "morton.h"
#include "prt/formats/iso_layout.h"

namespace prt::iso::detail {

inline constexpr std::uint32_t k_code_level = pool::k_max_iso_level;

/// The root cube in double precision (from the stored floats, so the builder's cells and corners
/// are exactly the ones the runtime's normalized coordinates describe).
struct Frame {
    double lo[3] = {0, 0, 0};
    double size = 1.0;

    /// Sets the cube (and the per-level tables: ldexp is slow in the inner loops).
    void set(const double corner[3], double edge_length) {
        for (int a = 0; a < 3; ++a) lo[a] = corner[a];
        size = edge_length;
        for (std::uint32_t l = 0; l <= k_code_level + 1; ++l) {
            m_edge[l] = std::ldexp(size, -static_cast<int>(l));
            m_cells[l] = std::ldexp(1.0, static_cast<int>(l));
        }
    }
    /// Edge of a cell at `level` (<= k_code_level + 1).
    double edge(std::uint32_t level) const { return m_edge[level]; }
    /// The cell at `level` holding coordinate v along `axis`, clamped to [0, 2^level - 1].
    std::uint32_t cell(double v, int axis, std::uint32_t level) const {
        const double q = std::floor((v - lo[axis]) / size * m_cells[level]);
        const double top = m_cells[level] - 1.0;
        return static_cast<std::uint32_t>(std::clamp(std::isfinite(q) ? q : 0.0, 0.0, top));
    }
    /// Box of the cell (x, y, z) at `level`.
    void box(std::uint32_t level, std::uint32_t x, std::uint32_t y, std::uint32_t z, double blo[3],
             double bhi[3]) const {
        const double e = edge(level);
        const std::uint32_t c[3] = {x, y, z};
        for (int a = 0; a < 3; ++a) {
            blo[a] = lo[a] + e * c[a];
            bhi[a] = lo[a] + e * (c[a] + 1.0);
        }
    }

private:
    double m_edge[k_code_level + 2] = {};
    double m_cells[k_code_level + 2] = {};
};

/// exp(x) for -700 <= x <= 0 (the caller guarantees it), relative error below 1e-15: 2^n exp(r) with
/// n = round(x / ln 2) and r = x - n ln 2 (Cody-Waite split), exp(r) by its Taylor series to
/// degree 12 (|r| <= ln 2 / 2). Branch-free arithmetic the compiler vectorizes; glibc's exp is a
/// call per weight and was 15% of prt-iso's time on the 1M-point sphere.
inline double exp_nonpositive(double x) {
    constexpr double k_magic = 6755399441055744.0;  // 1.5 * 2^52: adding it rounds to an integer
    constexpr double k_log2e = 1.4426950408889634;
    constexpr double k_ln2_hi = 6.93147180369123816490e-01, k_ln2_lo = 1.90821492927058770002e-10;
    const double t = x * k_log2e + k_magic;
    const double n = t - k_magic;
    const std::int64_t ni = std::bit_cast<std::int64_t>(t) - std::bit_cast<std::int64_t>(k_magic);
    const double r = (x - n * k_ln2_hi) - n * k_ln2_lo;
    double p = 1.0 / 479001600.0;  // 1/12!
    p = p * r + 1.0 / 39916800.0;
    p = p * r + 1.0 / 3628800.0;
    p = p * r + 1.0 / 362880.0;
    p = p * r + 1.0 / 40320.0;
    p = p * r + 1.0 / 5040.0;
    p = p * r + 1.0 / 720.0;
    p = p * r + 1.0 / 120.0;
    p = p * r + 1.0 / 24.0;
    p = p * r + 1.0 / 6.0;
    p = p * r + 0.5;
    p = p * r + 1.0;
    p = p * r + 1.0;
    return p * std::bit_cast<double>(static_cast<std::uint64_t>(ni + 1023) << 52);
}

/// The first position in [from, end) whose code is >= value, searched outwards from `from`
/// (exponential then binary search): a few steps when the answer is near, as it is for the next
/// node of a row.
inline const std::uint64_t* gallop_lower_bound(const std::uint64_t* from, const std::uint64_t* end,
                                               std::uint64_t value) {
    std::size_t step = 1;
    const std::uint64_t* lo = from;
    while (lo < end && *lo < value) {
        const std::size_t left = static_cast<std::size_t>(end - lo);
        const std::uint64_t* probe = lo + std::min(step, left - 1);
        if (*probe >= value) return std::lower_bound(lo + 1, probe + 1, value);
        lo = probe + 1;
        step *= 2;
    }
    return lo;
}

/// Calls f(begin, end) for every non-empty range of `codes` (sorted level-K point codes) that
/// lies in a node at `level` overlapping the box [blo, bhi] (closed). Nodes are visited in x-y-z
/// loops; at most `max_per_axis`^3 of them (the caller picks a level coarse enough). The codes of
/// the box lie between those of its lowest and highest nodes (a Morton code grows with each
/// coordinate), and along a row they grow with x, so each node's range is searched from the row's
/// previous one inside the box's span: the ISO build's gathers spent half their time in full
/// binary searches over every point's code before.
template <class F>
void for_each_node_range(std::span<const std::uint64_t> codes, const Frame& frame, std::uint32_t level,
                         const double blo[3], const double bhi[3], F&& f) {
    std::uint32_t c0[3], c1[3];
    for (int a = 0; a < 3; ++a) {
        const double top = frame.lo[a] + frame.size;
        if (bhi[a] < frame.lo[a] || blo[a] > top) return;  // the box misses the root
        c0[a] = frame.cell(blo[a], a, level);
        c1[a] = frame.cell(bhi[a], a, level);
    }
    const std::uint32_t shift = 3 * (k_code_level - level);
    const std::uint64_t span = (std::uint64_t{1} << shift) - 1;
    const std::uint64_t* const base = codes.data();
    const std::uint64_t* const box_begin =
        std::lower_bound(base, base + codes.size(), pre::morton3(c0[0], c0[1], c0[2]) << shift);
    const std::uint64_t* const box_end =
        std::upper_bound(box_begin, base + codes.size(), (pre::morton3(c1[0], c1[1], c1[2]) << shift) + span);
    if (box_begin == box_end) return;
    for (std::uint32_t z = c0[2]; z <= c1[2]; ++z)
        for (std::uint32_t y = c0[1]; y <= c1[1]; ++y) {
            const std::uint64_t* from = box_begin;
            for (std::uint32_t x = c0[0]; x <= c1[0]; ++x) {
                const std::uint64_t first = pre::morton3(x, y, z) << shift;
                const std::uint64_t* b = gallop_lower_bound(from, box_end, first);
                if (b == box_end) break;  // the row's further nodes have larger codes
                from = b;
                if (*b > first + span) continue;
                const std::uint64_t* e = gallop_lower_bound(b, box_end, first + span + 1);
                from = e;
                f(static_cast<std::size_t>(b - base), static_cast<std::size_t>(e - base));
            }
        }
}

/// The deepest level (<= max_level) whose cells are at least `extent` / `parts` wide, so that a
/// box of that extent overlaps at most parts + 1 cells per axis.
inline std::uint32_t level_for_extent(const Frame& frame, double extent, double parts,
                                      std::uint32_t max_level) {
    if (!(extent > 0)) return max_level;
    const double ratio = frame.size * parts / extent;  // cells of edge size / 2^l >= extent / parts
    if (!(ratio >= 1.0)) return 0;
    const double l = std::floor(std::log2(ratio));
    return static_cast<std::uint32_t>(std::min<double>(l, max_level));
}

}  // namespace prt::iso::detail
