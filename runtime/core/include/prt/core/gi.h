// PointRT core: lookups into the precomputed global illumination of a model: the caustic octree
// (thesis 5.4.2, written by prt-photons) and the diffuse light map (thesis 5.3, prt-lightmap).
// Both are sparse octrees with every filled leaf at one level and an RGB value at each leaf corner
// (pool layout: prt/formats/gi_layout.h). A lookup descends top-down from the root (thesis 2.2.2)
// to the leaf holding the point and interpolates its 8 corners trilinearly: no neighbour search
// at render time (thesis 5.4.2: "much faster than the near neighbors search").
//
// Header-only, host + device (PRT_HD): no allocation, no recursion; the descent is bounded by
// the octree's depth (<= pool::k_max_gi_depth).
#pragma once

#include <cstdint>

#include "prt/core/config.h"
#include "prt/core/math.h"
#include "prt/formats/gi_layout.h"

namespace prt::core {

/// A non-owning view of one GI octree (caustic or light-map sections) of a model, local frame.
struct GiOctreeView {
    const std::uint32_t* nodes = nullptr;  ///< node words (pool_layout.h encoding), or null: no map
    std::uint32_t node_count = 0;
    const pool::GiLeaf* leaves = nullptr;
    std::uint32_t leaf_count = 0;
    std::uint32_t depth = 0;  ///< level of every filled leaf
    Vec3 root_min{0, 0, 0};
    float root_size = 1.0f;
    float inv_root_size = 1.0f;
    float scale = 1.0f;          ///< decoded corner value = RGB9E5 x scale
    float cos_threshold = 0.0f;  ///< lookups whose normal disagrees more with the leaf find nothing
};

/// The caustic octree of a model (prt-photons): corner irradiance from LS+D photon paths.
struct CausticView {
    GiOctreeView tree;
};

/// The diffuse light map of a model (prt-lightmap): corner indirect irradiance.
struct LightMapView {
    GiOctreeView tree;
};

/// Decodes a shared-exponent RGB9E5 word (red bits 0-8, green 9-17, blue 18-26, exponent 27-31,
/// bias 15): component = mantissa x 2^(exponent - 15 - 9).
PRT_HD PRT_INLINE Vec3 decode_rgb9e5(std::uint32_t v) {
    const int e = static_cast<int>(v >> 27) - 15 - 9;
    const float s = ldexpf(1.0f, e);
    return Vec3{static_cast<float>(v & 511u) * s, static_cast<float>((v >> 9) & 511u) * s,
                static_cast<float>((v >> 18) & 511u) * s};
}

/// Encodes a non-negative RGB triple as RGB9E5 (values above 65408 are clamped, negative and
/// non-finite components become 0). Host and device, so writers and tests share one definition.
PRT_HD inline std::uint32_t encode_rgb9e5(Vec3 c) {
    const auto sat = [](float x) {
        return x > 0.0f ? (x < 65408.0f ? x : 65408.0f) : 0.0f;
    };  // (511/512) 2^16; NaN -> 0
    const float r = sat(c.x), g = sat(c.y), b = sat(c.z);
    const float m = fmaxf(r, fmaxf(g, b));
    if (!(m > 0.0f)) return 0u;
    int exp_shared = 0;
    frexpf(m, &exp_shared);  // m = f x 2^exp_shared, f in [0.5, 1)
    int e = exp_shared + 15;
    if (e < 0) e = 0;
    float s = ldexpf(1.0f, e - 15 - 9);
    if (floorf(m / s + 0.5f) >= 512.0f) {
        ++e;
        s *= 2.0f;
    }
    if (e > 31) {  // only reachable through rounding of the clamp
        e = 31;
        s = ldexpf(1.0f, 31 - 15 - 9);
    }
    const auto q = [s](float x) {
        const float v = floorf(x / s + 0.5f);
        return static_cast<std::uint32_t>(v < 511.0f ? v : 511.0f);
    };
    return q(r) | (q(g) << 9) | (q(b) << 18) | (static_cast<std::uint32_t>(e) << 27);
}

/// thesis 5.4.2: finds the leaf holding local point `p` and interpolates its corner values
/// trilinearly. `n` is the unit normal of the surface side being shaded (local frame). Returns
/// false (and leaves `out` unchanged) when there is no map, `p` is outside the root, `p` lies in
/// an empty leaf, or `n` disagrees with the leaf's normal (GiOctreeView::cos_threshold).
PRT_HD inline bool gi_lookup(const GiOctreeView& v, Vec3 p, Vec3 n, Vec3& out) {
    if (v.nodes == nullptr || v.node_count == 0) return false;
    const float fx = (p.x - v.root_min.x) * v.inv_root_size;
    const float fy = (p.y - v.root_min.y) * v.inv_root_size;
    const float fz = (p.z - v.root_min.z) * v.inv_root_size;
    if (!(fx >= 0.0f && fx <= 1.0f && fy >= 0.0f && fy <= 1.0f && fz >= 0.0f && fz <= 1.0f)) return false;
    const float cells = ldexpf(1.0f, static_cast<int>(v.depth));
    const std::uint32_t last = (1u << v.depth) - 1u;
    const float gx = fx * cells, gy = fy * cells, gz = fz * cells;
    const std::uint32_t ix = gx >= static_cast<float>(last) ? last : static_cast<std::uint32_t>(gx);
    const std::uint32_t iy = gy >= static_cast<float>(last) ? last : static_cast<std::uint32_t>(gy);
    const std::uint32_t iz = gz >= static_cast<float>(last) ? last : static_cast<std::uint32_t>(gz);
    // thesis 2.2.2: top-down descent, one bit of each cell coordinate per level.
    std::uint32_t node = v.nodes[0];
    for (std::uint32_t level = 0; level < v.depth; ++level) {
        if ((node >> pool::k_node_address_bits) != static_cast<std::uint32_t>(pool::NodeType::internal))
            break;
        const std::uint32_t bit = v.depth - 1u - level;
        const std::uint32_t c = ((ix >> bit) & 1u) | (((iy >> bit) & 1u) << 1) | (((iz >> bit) & 1u) << 2);
        const std::uint32_t child = (node & pool::k_node_address_max) + c;
        if (child >= v.node_count) return false;
        node = v.nodes[child];
    }
    if ((node >> pool::k_node_address_bits) != static_cast<std::uint32_t>(pool::NodeType::filled_leaf))
        return false;
    const std::uint32_t leaf_index = node & pool::k_node_address_max;
    if (leaf_index >= v.leaf_count) return false;
    const pool::GiLeaf& leaf = v.leaves[leaf_index];
    const Vec3 ln{leaf.normal[0] * (1.0f / 127.0f), leaf.normal[1] * (1.0f / 127.0f),
                  leaf.normal[2] * (1.0f / 127.0f)};
    if (length2(ln) > 0.25f && dot(ln, n) < v.cos_threshold * length(ln)) return false;
    const float ax = clampf(gx - static_cast<float>(ix), 0.0f, 1.0f);
    const float ay = clampf(gy - static_cast<float>(iy), 0.0f, 1.0f);
    const float az = clampf(gz - static_cast<float>(iz), 0.0f, 1.0f);
    Vec3 sum{0, 0, 0};
    PRT_UNROLL
    for (std::uint32_t c = 0; c < 8; ++c) {
        const float w =
            ((c & 1u) ? ax : 1.0f - ax) * ((c & 2u) ? ay : 1.0f - ay) * ((c & 4u) ? az : 1.0f - az);
        sum += decode_rgb9e5(leaf.corner[c]) * w;
    }
    out = sum * v.scale;
    return true;
}

/// thesis 5.4.2: caustic irradiance at local point `p` on the side with unit normal `n` (zero where
/// the map has nothing). The renderer multiplies it by the diffuse albedo.
PRT_HD PRT_INLINE Vec3 caustic_radiance(const CausticView& v, Vec3 p, Vec3 n) {
    Vec3 e{0, 0, 0};
    gi_lookup(v.tree, p, n, e);
    return e;
}

/// thesis 5.3: indirect irradiance at local point `p` with unit normal `n`. Returns false where the
/// light map has nothing for that point and side (the renderer then keeps its constant ambient).
PRT_HD PRT_INLINE bool light_map_irradiance(const LightMapView& v, Vec3 p, Vec3 n, Vec3& out) {
    return gi_lookup(v.tree, p, n, out);
}

}  // namespace prt::core
