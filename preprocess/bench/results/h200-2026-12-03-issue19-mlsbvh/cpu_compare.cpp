// Dev-VM check behind the README's first table: the kd walk against the BVH walk over the same pool
// (hits, normals, shadow answers bit for bit; nodes, leaves and rays/s per walk), the room from
// prt-bench's camera or the sphere from z = 3 (any second argument), then random rays. Built by hand:
// g++ -O2 -std=c++20 -fno-math-errno -march=native -Iruntime/core/include -Iruntime/host/include
//     -Iformats/include cpu_compare.cpp build/runtime/libprt_runtime.a build/formats/libprt_formats.a -lxxhash
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "prt/core/mls.h"
#include "prt/runtime/surface_pools.h"
using namespace prt;
using core::Vec3;
int main(int argc, char** argv) {
    auto pf = pool::PoolFile::open(argv[1]);
    core::MlsView vb = rt::load_mls_view(pf);
    core::MlsView vk = vb;
    vk.bvh_nodes = nullptr;
    vk.bvh_leaves = nullptr;
    std::printf("bvh nodes %u leaves %u depth %u\n", vb.bvh_node_count, vb.bvh_leaf_count, vb.bvh_depth);
    const bool sph = argc > 2;
    const int W = 256;
    Vec3 eye{0, 0, 0.9f}, at{0, -0.1f, -1.0f}, up{0, 1, 0};
    if (sph) {
        eye = Vec3{0, 0, 3};
        at = Vec3{0, 0, 0};
    }
    Vec3 f = core::normalize(at - eye), r = core::normalize(core::cross(f, up)), u = core::cross(r, f);
    float th = std::tan((sph ? 22.5f : 30.0f) * 3.14159265f / 180.0f);
    std::vector<Vec3> O, D;
    std::vector<float> TM;
    for (int y = 0; y < W; ++y)
        for (int x = 0; x < W; ++x) {
            float sx = ((x + 0.5f) / W * 2 - 1) * th, sy = (1 - (y + 0.5f) / W * 2) * th;
            O.push_back(eye);
            D.push_back(core::normalize(f + r * sx + u * sy));
            TM.push_back(core::k_inf);
        }
    // random rays through the model, short shadow-like t_max for half
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> U(-1, 1);
    for (int i = 0; i < 65536; ++i) {
        Vec3 o{U(rng) * 0.9f, U(rng) * 0.9f, U(rng) * 0.9f};
        Vec3 d = core::normalize(Vec3{U(rng), U(rng), U(rng)});
        O.push_back(o);
        D.push_back(d);
        TM.push_back(i % 2 ? core::k_inf : 0.3f + 0.5f * (U(rng) + 1));
    }
    core::MlsParams p;
    p.faces = core::k_mls_faces_by_ray;
    for (int set = 0; set < 2; ++set) {
        size_t a = set ? W * W : 0, e = set ? O.size() : W * W;
        unsigned long long sk = 0, sb = 0, ck = 0, cb = 0, ik = 0, ib = 0, diff = 0, occdiff = 0, n = e - a;
        double tk = 0, tb = 0;
        for (int pass = 0; pass < 2; ++pass) {
            auto t0 = std::chrono::steady_clock::now();
            for (size_t i = a; i < e; ++i) {
                core::MlsHit h;
                core::MlsStats st;
                core::trace_mls<float>(pass ? vb : vk, O[i], D[i], TM[i], false, p, h, st);
                if (pass) {
                    sb += st.traversal_steps;
                    cb += st.cells;
                    ib += st.intersections;
                } else {
                    sk += st.traversal_steps;
                    ck += st.cells;
                    ik += st.intersections;
                }
            }
            double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            (pass ? tb : tk) = s;
        }
        for (size_t i = a; i < e; ++i) {
            core::MlsHit h1, h2;
            core::MlsStats s1, s2;
            bool x1 = core::trace_mls<float>(vk, O[i], D[i], TM[i], false, p, h1, s1),
                 x2 = core::trace_mls<float>(vb, O[i], D[i], TM[i], false, p, h2, s2);
            if (x1 != x2 || (x1 && (h1.t != h2.t || h1.normal.x != h2.normal.x))) diff++;
            bool o1 = core::mls_occluded<float>(vk, O[i], D[i], TM[i], false, p, s1),
                 o2 = core::mls_occluded<float>(vb, O[i], D[i], TM[i], false, p, s2);
            if (o1 != o2) occdiff++;
        }
        std::printf(
            "%s: kd steps %.1f cells %.1f isect %.2f %.0f krays/s | bvh steps %.1f cells %.2f isect %.2f "
            "%.0f krays/s | hit diffs %llu occl diffs %llu of %llu\n",
            set ? "random" : "camera", double(sk) / n, double(ck) / n, double(ik) / n, n / tk / 1e3,
            double(sb) / n, double(cb) / n, double(ib) / n, n / tb / 1e3, diff, occdiff, n);
    }
}
