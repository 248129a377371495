// Test data for the brick builder and the brick traversal (issue 17): pools with a float splat
// octree built in memory, and the same pools with bricks added (float sections kept, so tests can
// compare both). Shared by tests/preprocess/bricks and tests/runtime/core/brick_trace_test.cpp.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "brick_build.h"
#include "octree_build.h"
#include "point_cloud.h"
#include "preprocess/splat/splat_test_data.h"
#include "prt/formats/octree_sections.h"
#include "prt/formats/pool.h"

namespace prt::test {

/// A pool with `cloud`'s points (radii given) and their float octree.
inline std::vector<std::byte> octree_pool_bytes(const pre::PointCloud& cloud, std::uint32_t max_leaf = 16,
                                                bool replicate = true) {
    pool::PoolWriter w;
    pre::write_point_sections(cloud, w);
    const pool::PoolFile points = pool::PoolFile::from_bytes(w.serialize(), "points");
    pre::OctreeParams params;
    params.max_leaf_splats = max_leaf;
    params.replicate = replicate;
    params.threads = 2;
    pre::SplatOctree octree = pre::build_octree(points.array<pool::Float3>(pool::SectionType::positions),
                                                points.array<pool::Float3>(pool::SectionType::normals),
                                                points.array<float>(pool::SectionType::radii), params);
    pre::add_octree_sections(std::move(octree), w);
    w.add_provenance("bricks_test", "0", "{}");
    return w.serialize();
}

/// A pool with points (sphere of radius 2, colours from the position) and their float octree.
inline std::vector<std::byte> octree_pool_bytes(std::size_t n, std::uint32_t max_leaf = 16,
                                                bool replicate = true) {
    const test::SplatSet s = sphere_points(n, 5, 2.0);
    pre::PointCloud cloud;
    for (std::size_t i = 0; i < s.positions.size(); ++i) {
        const pool::Float3& p = s.positions[i];
        cloud.positions.push_back({10.0 + p.x, -3.0 + p.y, p.z});
        cloud.colors.push_back(
            {std::uint8_t(64 + 40 * p.x), std::uint8_t(128 + 60 * p.y), std::uint8_t(i % 256), 255});
        cloud.radii.push_back(float(3.0 / std::sqrt(double(n))) * float(1 + i % 3));
    }
    cloud.normals = s.normals;
    return octree_pool_bytes(cloud, max_leaf, replicate);
}

/// The pool with bricks added, float sections kept (so the tests can compare) unless `keep_float`
/// is false (as prt-bricks without --keep-float).
inline std::vector<std::byte> bricked_bytes(const pool::PoolFile& in, std::uint32_t brick_splats,
                                            pre::BrickStats* stats = nullptr, bool keep_float = true,
                                            std::uint32_t lod_splats = pre::BrickParams{}.lod_splats,
                                            pre::BrickParams::Direct direct = pre::BrickParams{}.direct) {
    pre::BrickParams params;
    params.brick_splats = brick_splats;
    params.lod_splats = lod_splats;
    params.direct = direct;
    params.threads = 2;
    pre::BrickedOctree b = pre::build_bricks(pool::splat_octree(in, "test"),
                                             in.array<pool::Rgba8>(pool::SectionType::colors), params, stats);
    pool::PoolWriter w;
    w.carry_over(in);
    pre::add_brick_sections(std::move(b), w);
    if (!keep_float)
        for (const pool::SectionType t : {pool::SectionType::octree_info, pool::SectionType::octree_nodes,
                                          pool::SectionType::leaf_info, pool::SectionType::splats})
            w.remove(t);
    return w.serialize();
}

}  // namespace prt::test
