// gi-gather-bench: times the caustic gather (thesis 5.4.2: caustic octree + eq. 5.1-5.2 density
// estimates at every leaf corner) for N synthetic deposits: a cardioid-like bright curve plus a
// uniform background on a 2 x 2 floor, the shape a ring's caustic leaves. Not a test.
// Usage: gi-gather-bench [N=10000000] [DEPTH=10] [RADIUS_EDGES=1] [THREADS=0] [SHAPE=floor]
// SHAPE "shell": the same counts on a blurred sphere of radius 0.7 with varied colours and normals
// instead (deposits in every octant, off the cell boundaries), for equivalence checks.
// Also prints an FNV-1a hash of the tree (info, node words, leaves): equal hashes from two builds
// (or thread counts) mean byte-identical caustic octrees.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "photons.h"

namespace {

std::uint64_t fnv1a(std::uint64_t h, const void* data, std::size_t bytes) {
    const unsigned char* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
    return h;
}

}  // namespace

int main(int argc, char** argv) {
    using namespace prt;
    const std::uint64_t n = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 10000000ull;
    photons::GatherOptions g;
    g.depth = argc > 2 ? static_cast<std::uint32_t>(std::atoi(argv[2])) : 10;
    g.radius_edges = argc > 3 ? static_cast<float>(std::atof(argv[3])) : 1.0f;
    g.threads = argc > 4 ? static_cast<unsigned>(std::atoi(argv[4])) : 0;
    const bool shell = argc > 5 && std::string(argv[5]) == "shell";
    std::vector<photons::PhotonDeposit> deps(n);
    for (std::uint64_t i = 0; i < n; ++i) {
        const std::uint64_t h = photons::hash64(i);
        const float u = photons::unit_float(h), v = photons::unit_float(photons::hash64(h));
        photons::PhotonDeposit& d = deps[i];
        d = {};
        if (i % 4 != 0) {  // 3/4 on the cardioid r = 0.4 (1 - cos t), blurred
            const float t = 6.2831853f * u, r = 0.4f * (1 - std::cos(t)) + 0.01f * (v - 0.5f);
            d.position[0] = r * std::cos(t) + 0.3f;
            d.position[2] = r * std::sin(t);
        } else {
            d.position[0] = 2 * u - 1;
            d.position[2] = 2 * v - 1;
        }
        d.flux[0] = d.flux[1] = d.flux[2] = 1e-7f;
        d.normal[1] = 1;
        if (shell) {
            const float w = photons::unit_float(photons::hash64(h + 1));
            const float z = 2 * u - 1, s = std::sqrt(std::max(0.0f, 1 - z * z)), t = 6.2831853f * v;
            const float r = 0.7f + 0.02f * (w - 0.5f);
            const float n[3] = {s * std::cos(t), s * std::sin(t), z};
            for (int a = 0; a < 3; ++a) {
                d.position[a] = r * n[a];
                d.normal[a] = (i % 3 == 0 ? -1.0f : 1.0f) * n[a];
                d.flux[a] = 1e-7f * (1.0f + w * static_cast<float>(a));
            }
        }
    }
    double phases[5] = {0, 0, 0, 0, 0};
    g.phase_seconds = phases;
    const double root_min[3] = {-1, -1, -1};
    const auto t0 = std::chrono::steady_clock::now();
    const gi::GiOctree tree = photons::build_caustic_octree(deps, root_min, 2.0, g);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf(
        "gi-gather-bench: %llu deposits, depth %u, radius %.2f edges: %zu leaves, %zu nodes, %.3f s\n",
        static_cast<unsigned long long>(n), g.depth, g.radius_edges, tree.leaves.size(), tree.nodes.size(),
        s);
    std::printf(
        "gi-gather-bench: bin %.3f s, blocks %.3f s, densities + leaves %.3f s, encode %.3f s, "
        "octree %.3f s\n",
        phases[0], phases[1], phases[2], phases[3], phases[4]);
    std::uint64_t h = 0xcbf29ce484222325ull;
    h = fnv1a(h, &tree.info, sizeof tree.info);
    h = fnv1a(h, tree.nodes.data(), tree.nodes.size() * sizeof(tree.nodes[0]));
    h = fnv1a(h, tree.leaves.data(), tree.leaves.size() * sizeof(tree.leaves[0]));
    std::printf("gi-gather-bench: tree hash %016llx\n", static_cast<unsigned long long>(h));
    return 0;
}
