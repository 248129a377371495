// PointRT preprocess: the GI frame and surface points of a model, whatever its surface (issue 20;
// gi_frame.h says the rules).
#include "gi_frame.h"

#include <algorithm>
#include <cmath>

#include "gi_build.h"
#include "morton.h"
#include "prt/core/bezier.h"
#include "prt/error.h"
#include "prt/formats/patch_sections.h"

namespace prt::gi {

namespace {

/// Points sampled on every patch: an n x n grid of parameter cells per patch, at the cell centres,
/// n in [2, 512] from the patch's share of the model's area (estimated on a 4 x 4 grid).
SurfacePoints patch_samples(const pool::PoolFile& pool) {
    const pool::PatchSections ps = pool::validate_patches(pool);
    const std::size_t count = ps.nets.size();
    std::vector<double> area(count, 0.0);
    double total = 0.0;
    for (std::size_t p = 0; p < count; ++p) {
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) {
                const core::PatchEval e = core::patch_eval(ps.nets[p], (i + 0.5) / 4.0, (j + 0.5) / 4.0);
                area[p] += core::length(core::cross(e.qu, e.qv)) / 16.0;
            }
        total += area[p];
    }
    SurfacePoints out;
    out.on_surface = true;
    out.from = "patches";
    for (std::size_t p = 0; p < count; ++p) {
        const double share = total > 0.0 ? area[p] / total : 1.0 / static_cast<double>(count);
        const int n = std::clamp(static_cast<int>(std::ceil(std::sqrt(share * k_patch_samples))), 2, 512);
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                const double u = (i + 0.5) / n, v = (j + 0.5) / n;
                const core::PatchEval e = core::patch_eval(ps.nets[p], u, v);
                const core::DVec3 nn = core::patch_normal(ps.nets[p], u, v, e, core::DVec3{0, 0, 0});
                if (!core::is_finite(e.q) || !(core::length(nn) > 0.5)) continue;
                out.position.push_back(core::to_vec3(e.q));
                out.normal.push_back(core::to_vec3(nn));
            }
    }
    return out;
}

}  // namespace

SurfacePoints surface_points(const pool::PoolFile& pool) {
    if (pool.has(pool::SectionType::positions)) {
        const auto positions = pool.require<pool::Float3>(pool::SectionType::positions, "the GI maps");
        if (!pool.has(pool::SectionType::normals))
            throw Error(pool.label() +
                        ": the points have no normals, which light-map samples need (run prt-import)");
        const auto normals = pool.require<pool::Float3>(pool::SectionType::normals, "the GI maps");
        SurfacePoints out;
        out.from = "points";
        out.position.reserve(positions.size());
        out.normal.reserve(positions.size());
        for (std::size_t i = 0; i < positions.size(); ++i) {
            out.position.push_back(core::vec3(positions[i]));
            out.normal.push_back(core::vec3(normals[i]));
        }
        return out;
    }
    if (pool::has_patches(pool)) return patch_samples(pool);
    throw Error(
        pool.label() +
        ": no points and no patches to place the GI maps on (a bricked pool needs prt-bricks --keep-points "
        "for light maps)");
}

bool frame_needs_points(const pool::PoolFile& pool) {
    return !pool.has(pool::SectionType::octree_info) && !pool.has(pool::SectionType::brick_info);
}

std::uint32_t reference_level(const std::vector<core::Vec3>& points, const double root_min[3],
                              double root_size, double per_cell) {
    const std::uint32_t cap = pool::k_max_gi_depth - 2;
    if (points.empty()) return 1;
    // Morton keys at the finest level once, sorted; a level's occupied cells are the distinct keys
    // shifted down to it.
    const double scale = static_cast<double>(pre::k_morton_max + 1) / root_size;
    std::vector<std::uint64_t> keys(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
        std::uint32_t c[3];
        const float p[3] = {points[i].x, points[i].y, points[i].z};
        for (int a = 0; a < 3; ++a) {
            const double g = std::floor((static_cast<double>(p[a]) - root_min[a]) * scale);
            c[a] = static_cast<std::uint32_t>(std::clamp(g, 0.0, static_cast<double>(pre::k_morton_max)));
        }
        keys[i] = pre::morton3(c[0], c[1], c[2]);
    }
    std::sort(keys.begin(), keys.end());
    for (std::uint32_t level = 1; level <= cap; ++level) {
        const unsigned shift = 3u * (21u - level);
        std::size_t cells = 1;
        for (std::size_t i = 1; i < keys.size(); ++i) cells += (keys[i] >> shift) != (keys[i - 1] >> shift);
        if (static_cast<double>(points.size()) / static_cast<double>(cells) <= per_cell) return level;
    }
    return cap;
}

GiFrame gi_frame(const pool::PoolFile& pool, const SurfacePoints* points) {
    GiFrame f;
    for (const auto& [type, name] : {std::pair{pool::SectionType::octree_info, "the splat octree"},
                                     std::pair{pool::SectionType::brick_info, "the bricks"}}) {
        if (!pool.has(type)) continue;
        if (type == pool::SectionType::octree_info) {
            splat_root(pool, f.root_min, f.root_size, f.depth);
        } else {
            const auto info = pool.require<pool::BrickInfo>(type, "the GI maps");
            if (info.size() != 1) pool.fail(pool.find(type), "must hold exactly one element");
            for (int a = 0; a < 3; ++a) f.root_min[a] = info[0].root_min[a];
            f.root_size = info[0].root_size;
            f.depth = info[0].depth;
        }
        f.from = name;
        return f;
    }
    if (points == nullptr || points->position.empty())
        throw Error(pool.label() + ": no surface points to place the GI maps on");
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (const core::Vec3& p : points->position) {
        if (!core::is_finite(p)) continue;
        const double c[3] = {p.x, p.y, p.z};
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], c[a]);
            hi[a] = std::max(hi[a], c[a]);
        }
    }
    if (!(lo[0] <= hi[0])) throw Error(pool.label() + ": no finite surface points to place the GI maps on");
    const double edge = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-6});
    const double margin = edge / 64.0;
    // Rounded to float as GiInfo stores them, so the build bins in the cells lookups will find
    // (the margin keeps every point inside after rounding).
    f.root_size = static_cast<float>(edge + 2.0 * margin);
    for (int a = 0; a < 3; ++a) f.root_min[a] = static_cast<float>(0.5 * (lo[a] + hi[a]) - 0.5 * f.root_size);
    f.depth = reference_level(points->position, f.root_min, f.root_size);
    f.from = points->from == "patches" ? "the patches" : "the points";
    return f;
}

}  // namespace prt::gi
