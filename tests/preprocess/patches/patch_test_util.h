// Shared helpers of the patch tests: random nets, an independent bicubic evaluation (the power
// basis matrix form of seed 002, eq. 1, written out here, not bezier.h's Bernstein code), and
// building a pool image in memory.
#pragma once

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "patch_build.h"
#include "patch_pool.h"
#include "prt/core/patch.h"
#include "prt/formats/pool.h"
#include "prt/runtime/surface_pools.h"

namespace prt::patch_test {

using Net = pool::PatchControlNet;
using V3 = std::array<double, 3>;

inline V3 sub(const V3& a, const V3& b) {
    return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
inline V3 add(const V3& a, const V3& b) {
    return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}
inline V3 mul(const V3& a, double s) {
    return {a[0] * s, a[1] * s, a[2] * s};
}
inline double dot3(const V3& a, const V3& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline V3 cross3(const V3& a, const V3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm3(const V3& a) {
    return std::sqrt(dot3(a, a));
}
inline V3 unit3(const V3& a) {
    return mul(a, 1.0 / norm3(a));
}
inline V3 v3(const pool::PatchPoint& p) {
    return {p.x, p.y, p.z};
}
inline V3 v3(const core::DVec3& p) {
    return {p.x, p.y, p.z};
}
inline core::DVec3 dv(const V3& a) {
    return {a[0], a[1], a[2]};
}
inline pool::PatchPoint pp(const V3& a) {
    return {a[0], a[1], a[2]};
}

/// Q(u, v) = [U][M][P][M]^T[V]^T with U = [u^3 u^2 u 1] (seed 002, eq. 1), and its derivatives.
struct MatrixEval {
    V3 q, qu, qv;
};
inline MatrixEval matrix_eval(const Net& net, double u, double v) {
    static constexpr double m[4][4] = {{-1, 3, -3, 1}, {3, -6, 3, 0}, {-3, 3, 0, 0}, {1, 0, 0, 0}};
    const double U[4] = {u * u * u, u * u, u, 1}, dU[4] = {3 * u * u, 2 * u, 1, 0};
    const double W[4] = {v * v * v, v * v, v, 1}, dW[4] = {3 * v * v, 2 * v, 1, 0};
    double a[4], da[4], b[4], db[4];  // U M and V M
    for (int k = 0; k < 4; ++k) {
        a[k] = da[k] = b[k] = db[k] = 0;
        for (int r = 0; r < 4; ++r) {
            a[k] += U[r] * m[r][k], da[k] += dU[r] * m[r][k];
            b[k] += W[r] * m[r][k], db[k] += dW[r] * m[r][k];
        }
    }
    MatrixEval e{{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            const V3 p = v3(net.p[4 * i + j]);
            e.q = add(e.q, mul(p, a[i] * b[j]));
            e.qu = add(e.qu, mul(p, da[i] * b[j]));
            e.qv = add(e.qv, mul(p, a[i] * db[j]));
        }
    return e;
}

inline Net random_net(std::mt19937_64& rng, double scale = 1.0) {
    std::uniform_real_distribution<double> jitter(-0.3, 0.3);
    Net n{};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            n.p[4 * i + j] = {scale * (i / 3.0 + 0.2 * jitter(rng)), scale * (j / 3.0 + 0.2 * jitter(rng)),
                              scale * jitter(rng)};
    return n;
}

/// Q(u, v) = o + u a + v b (a linearly parametrized parallelogram).
inline Net planar_net(const V3& o, const V3& a, const V3& b) {
    Net n{};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) n.p[4 * i + j] = pp(add(o, add(mul(a, i / 3.0), mul(b, j / 3.0))));
    return n;
}

/// The hyperbolic paraboloid Q(u, v) = (u, v, u v) as a bicubic (degree-elevated bilinear).
inline Net saddle_net() {
    Net n{};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) n.p[4 * i + j] = {i / 3.0, j / 3.0, (i / 3.0) * (j / 3.0)};
    return n;
}

/// A pool built in memory from nets (world frame) and its validated view.
struct BuiltPool {
    pool::PoolFile file;
    core::PatchView view;
    std::array<double, 3> origin;
};

inline BuiltPool build_pool(std::vector<Net> nets, std::uint32_t depth = 6, bool orient = false) {
    patches::BuildOptions o;
    o.depth = depth;
    o.orient = orient;
    const patches::PatchModel m = patches::build_patch_model(std::move(nets), o);
    pool::PoolWriter w;
    patches::write_patch_sections(m, w);
    w.add_provenance("patch_test", "0", "{}");
    pool::PoolFile f = pool::PoolFile::from_bytes(w.serialize(), "test.pool");
    const core::PatchView view = rt::load_patch_view(f);
    return {std::move(f), view, {m.model_info.origin[0], m.model_info.origin[1], m.model_info.origin[2]}};
}

/// A ray in world coordinates turned into the pool's local frame.
inline core::PatchRay local_ray(const BuiltPool& b, const V3& origin, const V3& dir, double t_max = 1e30,
                                bool inside = false) {
    return core::PatchRay{dv(sub(origin, {b.origin[0], b.origin[1], b.origin[2]})), dv(dir), t_max,
                          inside ? 1u : 0u};
}

}  // namespace prt::patch_test
