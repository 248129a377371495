// PointRT preprocess: the CPU backend's probe-hit pass of probe-ray culling (thesis 3.4), the
// inner loop of prt-cull on the CPU (see cull_build.h for the method).
#pragma once

#include <cstdint>
#include <vector>

#include "prt/core/cull.h"

namespace prt::pre {

/// The CPU backend's probe-hit pass (cull.h's cull_detail::probe_hits, which the CUDA backend runs).
/// The scalar pass branches on every splat test (face, ray range, radius) and took about 15 ns a
/// test on the 2-core development machine, 86 % of prt-cull's time. This one copies a leaf's splats
/// once into four-wide structure-of-arrays blocks and tests a probe line against four splats per
/// step (GCC vector extensions: SSE on x86-64) without branches, with intersect_splat's operations in the
/// same order (prt_cull compiles with -ffp-contract=off, as the CUDA backend uses --fmad=false), then reduces
/// the hits in splat order as probe_hits does: the same SideHits, so the same replicas are kept
/// (tests/preprocess/splat/cull_test.cpp, CullProbeHits.*). Not thread-safe: one per worker.
class LeafProbeHits {
public:
    void operator()(const core::OctreeView& v, std::uint32_t begin, std::uint32_t end,
                    const std::uint8_t* keep, core::Vec3 o, core::Vec3 d, float t0, float t1,
                    core::cull_detail::SideHits hits[2], core::CullCounters& c) {
        if (begin != m_begin || end != m_end || v.splats != m_splats) load(v.splats, begin, end);
        for (int side = 0; side < 2; ++side)
            hits[side] = core::cull_detail::SideHits{core::k_inf, 0.0f, core::k_inf, false};
        c.splat_tests += end - begin;
        const F4 ox = broadcast(o.x), oy = broadcast(o.y), oz = broadcast(o.z);
        const F4 dx = broadcast(d.x), dy = broadcast(d.y), dz = broadcast(d.z);
        const F4 lo = broadcast(t0), hi = broadcast(t1), zero = broadcast(0.0f);
        const I4 sign = broadcast_int(INT32_MIN), one = broadcast_int(1), two = broadcast_int(2);
        for (std::size_t b = 0; b < m_blocks.size(); ++b) {
            const Block& k = m_blocks[b];
            const F4 dn = dx * k.nx + dy * k.ny + dz * k.nz;  // dot(d, n)
            const F4 ocx = ox - k.px, ocy = oy - k.py, ocz = oz - k.pz;
            const F4 th = -(ocx * k.nx + ocy * k.ny + ocz * k.nz) / dn;
            const F4 pcx = ocx + dx * th, pcy = ocy + dy * th, pcz = ocz + dz * th;
            const F4 x2 = pcx * pcx + pcy * pcy + pcz * pcz;
            // face_expected(dn, dn > 0) fails only for dn = 0 (NaN gives a NaN th, refused below)
            const I4 hit = (dn != zero) & (th >= lo) & (th <= hi) & (x2 <= k.r2) & (k.r2 > zero);
            const I4 side = dn > zero;
            m_s[b] = reinterpret_cast<F4>(reinterpret_cast<I4>(th) ^ (side & sign));  // side 1 measures -t
            m_lane[b] = hit & (one | (side & two));  // 0: no hit, 1: a hit on side 0, 3: on side 1
        }
        // The hits in splat order (probe_hits' reduction: ties keep the first splat's radius).
        const pool::Splat* splats = v.splats;
        for (std::size_t b = 0; b < m_blocks.size(); ++b) {
            const I4 lanes = m_lane[b];
            if ((lanes[0] | lanes[1] | lanes[2] | lanes[3]) == 0) continue;
            for (std::uint32_t l = 0; l < 4; ++l) {
                const std::int32_t lane = lanes[l];
                if (lane == 0) continue;
                const float sd = m_s[b][l];
                const std::uint32_t i = begin + static_cast<std::uint32_t>(b) * 4 + l;
                core::cull_detail::SideHits& h = hits[lane >> 1];
                if (sd < h.near_s) {
                    h.near_s = sd;
                    h.near_r = splats[i].radius;
                }
                if (keep[i] >= core::k_keep_centre && sd < h.kept_s) h.kept_s = sd;
                h.centre = h.centre || keep[i] == core::k_keep_centre;
            }
        }
    }

private:
    using F4 = float __attribute__((vector_size(16)));
    using I4 = std::int32_t __attribute__((vector_size(16)));
    struct Block {
        F4 px, py, pz, nx, ny, nz, r2;
    };
    static F4 broadcast(float x) { return F4{x, x, x, x}; }
    static I4 broadcast_int(std::int32_t x) { return I4{x, x, x, x}; }

    void load(const pool::Splat* splats, std::uint32_t begin, std::uint32_t end) {
        m_splats = splats;
        m_begin = begin;
        m_end = end;
        const std::size_t blocks = (end - begin + 3) / 4;
        m_blocks.assign(blocks, Block{});  // padding lanes: zero normal and radius, never a hit
        m_s.resize(blocks);
        m_lane.resize(blocks);
        for (std::uint32_t i = begin; i < end; ++i) {
            const pool::Splat& s = splats[i];
            Block& k = m_blocks[(i - begin) / 4];
            const std::uint32_t l = (i - begin) % 4;
            k.px[l] = s.position.x;
            k.py[l] = s.position.y;
            k.pz[l] = s.position.z;
            k.nx[l] = s.normal.x;
            k.ny[l] = s.normal.y;
            k.nz[l] = s.normal.z;
            k.r2[l] = s.radius * s.radius;
        }
    }

    const pool::Splat* m_splats = nullptr;
    std::uint32_t m_begin = 0, m_end = 0;
    std::vector<Block> m_blocks;
    std::vector<F4> m_s;
    std::vector<I4> m_lane;
};

}  // namespace prt::pre
