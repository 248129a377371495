#include "prt/runtime/leaf_bounds.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "prt/parallel.h"

namespace prt::rt {

namespace {

constexpr double k_dinf = std::numeric_limits<double>::infinity();

/// A leaf whose splats the tests must always read (non-finite data, or no cone and no slab).
core::LeafBounds open_bounds() {
    return core::LeafBounds{0.0f,
                            0.0f,
                            1.0f,
                            2.0f,
                            -std::numeric_limits<float>::infinity(),
                            std::numeric_limits<float>::infinity(),
                            0,
                            0};
}

core::LeafBounds leaf(const core::OctreeView& v, std::uint32_t begin, std::uint32_t end) {
    // Pass 1: which splats can ever be hit (intersect_splat needs r*r > 0 and dot(d, n) != 0),
    // and the mean of their unit normals.
    double sum[3] = {0, 0, 0};
    std::uint32_t hittable = 0;
    for (std::uint32_t i = begin; i < end; ++i) {
        const pool::Splat& s = v.splats[i];
        const float r2 = s.radius * s.radius;
        const double n[3] = {s.normal.x, s.normal.y, s.normal.z};
        if (!(r2 > 0.0f) || std::isnan(n[0]) || std::isnan(n[1]) || std::isnan(n[2])) continue;
        if (n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0) continue;
        if (!std::isfinite(s.radius) || !std::isfinite(s.position.x) || !std::isfinite(s.position.y) ||
            !std::isfinite(s.position.z) || !std::isfinite(n[0]) || !std::isfinite(n[1]) ||
            !std::isfinite(n[2]))
            return open_bounds();
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int a = 0; a < 3; ++a) sum[a] += n[a] / len;
        ++hittable;
    }
    if (hittable == 0) {  // nothing here can be hit: every ray may pass
        return core::LeafBounds{0.0f, 0.0f, 1.0f, -1.0f, 1.0f, -1.0f, 0, 0};
    }
    double axis[3] = {0, 0, 1};
    const double slen = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
    if (slen > 1e-6 * hittable) {
        for (int a = 0; a < 3; ++a) axis[a] = sum[a] / slen;
    }
    // The axis as the core reads it (float), renormalized in double: cone and slab are computed
    // about exactly the stored vector.
    const float af[3] = {static_cast<float>(axis[0]), static_cast<float>(axis[1]),
                         static_cast<float>(axis[2])};
    const double alen = std::sqrt(double(af[0]) * af[0] + double(af[1]) * af[1] + double(af[2]) * af[2]);
    // Pass 2: the widest normal from the axis, and the slab of the disks along it.
    double min_cos = k_dinf, lo = k_dinf, hi = -k_dinf, scale = 0;
    for (std::uint32_t i = begin; i < end; ++i) {
        const pool::Splat& s = v.splats[i];
        const double n[3] = {s.normal.x, s.normal.y, s.normal.z};
        if (!(s.radius * s.radius > 0.0f) || std::isnan(n[0]) || std::isnan(n[1]) || std::isnan(n[2]))
            continue;
        if (n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0) continue;
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        const double c = (af[0] * n[0] + af[1] * n[1] + af[2] * n[2]) / (len * alen);
        min_cos = std::min(min_cos, c);
        // A disk of radius r with unit normal n spans r * sqrt(1 - (a.n)^2) either side of its centre
        // along the unit axis a.
        const double centre =
            (af[0] * double(s.position.x) + af[1] * double(s.position.y) + af[2] * double(s.position.z)) /
            alen;
        const double extent = std::fabs(double(s.radius)) * std::sqrt(std::max(0.0, 1.0 - c * c));
        lo = std::min(lo, centre - extent);
        hi = std::max(hi, centre + extent);
        scale = std::max({scale, std::fabs(double(s.position.x)), std::fabs(double(s.position.y)),
                          std::fabs(double(s.position.z)), std::fabs(double(s.radius))});
    }
    core::LeafBounds b{};
    b.axis_x = af[0];
    b.axis_y = af[1];
    b.axis_z = af[2];
    // Cone: normals within theta of the axis, cos(theta) = min_cos. A margin of 1e-4 covers the
    // float rounding of the core's dot products (and the axis not being exactly unit in float).
    if (min_cos > 1e-3) {
        b.sin_theta = static_cast<float>(std::sqrt(std::max(0.0, 1.0 - min_cos * min_cos)) + 1e-4);
    } else {
        b.sin_theta = 2.0f;  // a half-space or more: never passes
    }
    // Slab, widened by a relative margin (the float splat data and the core's float arithmetic)
    // and rounded outward to float.
    const double margin = 1e-6 * scale + 1e-6 * std::max(std::fabs(lo), std::fabs(hi));
    b.lo = std::nextafter(static_cast<float>(lo - margin), -std::numeric_limits<float>::infinity());
    b.hi = std::nextafter(static_cast<float>(hi + margin), std::numeric_limits<float>::infinity());
    return b;
}

}  // namespace

std::vector<core::LeafBounds> build_leaf_bounds(const core::OctreeView& v, unsigned threads) {
    std::vector<core::LeafBounds> out(v.filled_leaves);
    if (v.filled_leaves == 0 || v.leaf_info == nullptr || v.splats == nullptr) return out;
    parallel_chunks(v.filled_leaves, 4096, resolve_threads(threads),
                    [&](std::size_t first, std::size_t last, unsigned) {
                        for (std::size_t l = first; l < last; ++l) {
                            std::uint32_t b = v.leaf_info[l], e = v.leaf_info[l + 1];
                            e = std::min(e, v.splat_count);  // as core::leaf_splats clamps
                            b = std::min(b, e);
                            out[l] = leaf(v, b, e);
                            out[l].begin = b;
                            out[l].end = e;
                        }
                    });
    return out;
}

namespace {

/// The leaf bounds of a brick opened by core::open_brick.
std::vector<core::LeafBounds> opened_brick_bounds(const core::BrickSplats& src, core::OctreeView brick,
                                                  std::vector<pool::Splat>& decoded) {
    decoded.resize(brick.splat_count);
    for (std::uint32_t i = 0; i < brick.splat_count; ++i) decoded[i] = src.load(i);
    brick.splats = decoded.data();
    return build_leaf_bounds(brick, 1);
}

}  // namespace

std::vector<core::LeafBounds> build_brick_leaf_bounds(const core::BrickView& v,
                                                      std::vector<std::uint32_t>& first, unsigned threads) {
    first.assign(std::size_t{v.brick_count} + 1, 0);
    for (std::uint32_t b = 0; b < v.brick_count; ++b) first[b + 1] = first[b] + v.table[b].leaf_count;
    std::vector<core::LeafBounds> out(first.back());
    parallel_chunks(
        v.brick_count, 1, resolve_threads(threads), [&](std::size_t b0, std::size_t b1, unsigned) {
            std::vector<pool::Splat> decoded;
            for (std::size_t b = b0; b < b1; ++b) {
                core::BrickSplats src;
                core::OctreeView brick;
                if (!core::open_brick(v, static_cast<std::uint32_t>(b), src, brick)) continue;
                const std::vector<core::LeafBounds> leaves = opened_brick_bounds(src, brick, decoded);
                std::copy(leaves.begin(), leaves.end(), out.begin() + first[b]);
            }
        });
    return out;
}

std::vector<core::LeafBounds> build_one_brick_leaf_bounds(const pool::BrickEntry& entry,
                                                          const unsigned char* payload) {
    const unsigned char* resident[1] = {payload};
    core::BrickView v;
    v.table = &entry;
    v.brick_count = 1;
    v.resident = resident;
    core::BrickSplats src;
    core::OctreeView brick;
    std::vector<pool::Splat> decoded;
    if (!core::open_brick(v, 0, src, brick)) return {};
    return opened_brick_bounds(src, brick, decoded);
}

}  // namespace prt::rt
