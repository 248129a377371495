#include "prt/runtime/leaf_bounds.h"

#include <algorithm>

#include "prt/core/leaf_bounds.h"
#include "prt/parallel.h"

namespace prt::rt {

std::vector<core::LeafBounds> build_leaf_bounds(const core::OctreeView& v, unsigned threads) {
    std::vector<core::LeafBounds> out(v.filled_leaves);
    if (v.filled_leaves == 0 || v.leaf_info == nullptr || v.splats == nullptr) return out;
    parallel_chunks(v.filled_leaves, 4096, resolve_threads(threads),
                    [&](std::size_t first, std::size_t last, unsigned) {
                        for (std::size_t l = first; l < last; ++l) {
                            std::uint32_t b = v.leaf_info[l], e = v.leaf_info[l + 1];
                            e = std::min(e, v.splat_count);  // as core::leaf_splats clamps
                            b = std::min(b, e);
                            out[l] = core::leaf_bounds_of(core::SplatArray{v.splats}, b, e);
                            out[l].begin = b;
                            out[l].end = e;
                        }
                    });
    return out;
}

namespace {

/// The compact leaf bounds of a brick opened by core::open_brick, over its splats decoded once.
std::vector<core::BrickLeafBounds> opened_brick_bounds(const core::BrickSplats& src,
                                                       const core::OctreeView& brick,
                                                       std::vector<pool::Splat>& decoded) {
    decoded.resize(brick.splat_count);
    for (std::uint32_t i = 0; i < brick.splat_count; ++i) decoded[i] = src.load(i);
    std::vector<core::BrickLeafBounds> out(brick.filled_leaves);
    for (std::uint32_t l = 0; l < brick.filled_leaves; ++l) {
        std::uint32_t e = std::min(brick.leaf_info[l + 1], brick.splat_count);
        std::uint32_t b = std::min(brick.leaf_info[l], e);
        out[l] = core::brick_leaf_bounds_of(core::SplatArray{decoded.data()}, b, e);
    }
    return out;
}

}  // namespace

std::vector<core::BrickLeafBounds> build_brick_leaf_bounds(const core::BrickView& v,
                                                           std::vector<std::uint32_t>& first,
                                                           unsigned threads) {
    first.assign(std::size_t{v.brick_count} + 1, 0);
    for (std::uint32_t b = 0; b < v.brick_count; ++b) first[b + 1] = first[b] + v.table[b].leaf_count;
    std::vector<core::BrickLeafBounds> out(first.back());
    parallel_chunks(
        v.brick_count, 1, resolve_threads(threads), [&](std::size_t b0, std::size_t b1, unsigned) {
            std::vector<pool::Splat> decoded;
            for (std::size_t b = b0; b < b1; ++b) {
                core::BrickSplats src;
                core::OctreeView brick;
                if (!core::open_brick(v, static_cast<std::uint32_t>(b), src, brick)) continue;
                const std::vector<core::BrickLeafBounds> leaves = opened_brick_bounds(src, brick, decoded);
                std::copy(leaves.begin(), leaves.end(), out.begin() + first[b]);
            }
        });
    return out;
}

std::vector<core::BrickLeafBounds> build_one_brick_leaf_bounds(const pool::BrickEntry& entry,
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
