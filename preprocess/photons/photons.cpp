// PointRT prt-photons: photon shooting on the CPU (or through prt_photons_cuda) and the caustic
// octree (thesis 5.4).
#include "photons.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>

#include "parallel.h"
#include "prt/error.h"
#include "prt/tool.h"

#if defined(PRT_HAVE_CUDA)
#include "prt/cuda/photons_cuda.h"
#endif

namespace prt::photons {

namespace {

constexpr double k_pi = 3.14159265358979323846;

void add_tally(PhotonTally& t, const PhotonTallyF& f) {
    const core::Vec3* src[6] = {&f.emitted, &f.direct, &f.deposited, &f.absorbed, &f.escaped, &f.truncated};
    double* dst[6] = {t.emitted, t.direct, t.deposited, t.absorbed, t.escaped, t.truncated};
    for (int k = 0; k < 6; ++k) {
        dst[k][0] += src[k]->x;
        dst[k][1] += src[k]->y;
        dst[k][2] += src[k]->z;
    }
    t.deposits += f.deposits;
    t.specular_hits += f.specular_hits;
    t.rays += f.rays;
}

void add_tally(PhotonTally& t, const PhotonTally& o) {
    for (int a = 0; a < 3; ++a) {
        t.emitted[a] += o.emitted[a];
        t.direct[a] += o.direct[a];
        t.deposited[a] += o.deposited[a];
        t.absorbed[a] += o.absorbed[a];
        t.escaped[a] += o.escaped[a];
        t.truncated[a] += o.truncated[a];
    }
    t.deposits += o.deposits;
    t.specular_hits += o.specular_hits;
    t.rays += o.rays;
}

float luminance(const float c[3]) {
    return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
}

}  // namespace

float solid_angle_norm(std::uint32_t face_res) {
    double sum = 0.0;
    const double h = 2.0 / face_res;
    for (std::uint32_t y = 0; y < face_res; ++y) {
        const double t = -1.0 + (y + 0.5) * h;
        for (std::uint32_t x = 0; x < face_res; ++x) {
            const double s = -1.0 + (x + 0.5) * h;
            const double q = 1.0 + s * s + t * t;
            sum += h * h / (q * std::sqrt(q));
        }
    }
    return static_cast<float>(4.0 * k_pi / (6.0 * sum));
}

std::string resolve_backend(const std::string& requested, std::string* why) {
    if (requested == "cpu") return "cpu";
#if defined(PRT_HAVE_CUDA)
    std::string reason;
    if (cuda::photons_device_available(&reason)) return "cuda";
    if (requested == "cuda") throw Error("--backend cuda: " + reason);
    if (why) *why = reason;
    return "cpu";
#else
    if (requested == "cuda") throw Error("--backend cuda: this build has no CUDA backend");
    if (why) *why = "this build has no CUDA backend";
    return "cpu";
#endif
}

ShootResult shoot_photons(const core::SceneView& scene, const ShootOptions& options,
                          const std::function<void(std::uint64_t, std::uint64_t)>& progress) {
    ShootResult result;
    ShootParams params = options.params;
    params.solid_angle_norm = solid_angle_norm(params.face_res);
    const std::uint64_t per_light = photons_per_light(params);
    const std::uint64_t total = per_light * scene.light_count;
    result.tally.photons = total;
    const std::string backend = resolve_backend(options.backend);
    const double start = tool::now_seconds();
    if (backend == "cuda") {
#if defined(PRT_HAVE_CUDA)
        cuda::PhotonsCudaResult r = cuda::shoot_photons_cuda(scene, params, progress);
        result.deposits = std::move(r.deposits);
        add_tally(result.tally, r.tally);
        result.tally.photons = total;
        result.backend = r.device;
        result.kernel_seconds = r.kernel_seconds;
#endif
    } else {
        const unsigned threads = pre::resolve_threads(options.threads);
        std::vector<std::vector<PhotonDeposit>> per_worker(threads);
        std::vector<PhotonTally> tallies(threads);
        std::atomic<std::uint64_t> done{0};
        constexpr std::size_t k_chunk = 1 << 14;
        pre::parallel_chunks(total, k_chunk, threads,
                             [&](std::size_t begin, std::size_t end, unsigned worker) {
                                 PhotonTallyF f;
                                 std::vector<PhotonDeposit>& out = per_worker[worker];
                                 for (std::size_t g = begin; g < end; ++g) {
                                     const std::uint32_t light = static_cast<std::uint32_t>(g / per_light);
                                     trace_photon(scene, params, light, g - light * per_light, f,
                                                  [&](const PhotonDeposit& d) { out.push_back(d); });
                                     // Float tallies stay exact enough over a few thousand photons; flush
                                     // often.
                                     if (((g - begin) & 1023u) == 1023u) {
                                         add_tally(tallies[worker], f);
                                         f = PhotonTallyF{};
                                     }
                                 }
                                 add_tally(tallies[worker], f);
                                 const std::uint64_t d = done.fetch_add(end - begin) + (end - begin);
                                 if (worker == 0 && progress) progress(d, total);
                             });
        for (unsigned w = 0; w < threads; ++w) {
            result.deposits.insert(result.deposits.end(), per_worker[w].begin(), per_worker[w].end());
            std::vector<PhotonDeposit>().swap(per_worker[w]);
            add_tally(result.tally, tallies[w]);
        }
        result.backend = "cpu (" + std::to_string(threads) + " threads)";
    }
    result.seconds = tool::now_seconds() - start;
    if (backend != "cuda") result.kernel_seconds = result.seconds;
    return result;
}

GiOctree build_caustic_octree(std::span<const PhotonDeposit> deposits, const double root_min[3],
                              double root_size, const GatherOptions& options) {
    const std::uint32_t depth = options.depth;
    if (depth > pool::k_max_gi_depth)
        throw Error("caustic octree depth " + std::to_string(depth) + " above " +
                    std::to_string(pool::k_max_gi_depth));
    if (!(options.radius_edges > 0.0f)) throw Error("gather radius must be positive");
    const unsigned threads = pre::resolve_threads(options.threads);
    double mark = tool::now_seconds();
    auto phase = [&](int k) {
        const double now = tool::now_seconds();
        if (options.phase_seconds) options.phase_seconds[k] = now - mark;
        mark = now;
    };
    const CellBins bins = gi::bin_points(deposits.size(), root_min, root_size, depth,
                                         [&](std::size_t i) { return deposits[i].position; });
    const double ge = options.radius_edges;
    const std::int64_t reach = static_cast<std::int64_t>(std::ceil(ge));
    const std::int64_t cells = std::int64_t{1} << depth;

    // The deposits in cell order, as offsets inside their cell (floats keep full precision there
    // at any depth) with their flux and luminance-weighted normal: the density loop reads them
    // sequentially, cell by cell.
    struct Packed {
        float frac[3];
        float flux[3];
        float normal[3];  ///< luminance x normal
        float lum;
    };
    std::vector<Packed> packed(deposits.size());
    pre::parallel_chunks(bins.cell_keys.size(), 4096, threads,
                         [&](std::size_t begin, std::size_t end, unsigned) {
                             for (std::size_t c = begin; c < end; ++c) {
                                 std::uint32_t cell[3];
                                 gi::demorton3(bins.cell_keys[c], cell[0], cell[1], cell[2]);
                                 for (std::uint32_t j = bins.cell_begin[c]; j < bins.cell_begin[c + 1]; ++j) {
                                     const PhotonDeposit& d = deposits[bins.order[j]];
                                     double g[3];
                                     bins.grid(d.position, g);
                                     Packed& p = packed[j];
                                     p.lum = luminance(d.flux);
                                     for (int a = 0; a < 3; ++a) {
                                         p.frac[a] = static_cast<float>(g[a] - cell[a]);
                                         p.flux[a] = d.flux[a];
                                         p.normal[a] = p.lum * d.normal[a];
                                     }
                                 }
                             }
                         });
    phase(0);
    // Corners a deposit can reach: lattice points within g of some deposit's cell.
    std::vector<std::uint64_t> corner_keys;
    corner_keys.reserve(bins.cell_keys.size() * 8);
    for (std::uint64_t key : bins.cell_keys) {
        std::uint32_t c[3];
        gi::demorton3(key, c[0], c[1], c[2]);
        std::int64_t lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::max<std::int64_t>(0, c[a] - reach + 1);
            hi[a] = std::min<std::int64_t>(cells, c[a] + reach);
        }
        for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
            for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
                for (std::int64_t x = lo[0]; x <= hi[0]; ++x)
                    corner_keys.push_back(gi::morton3(static_cast<std::uint32_t>(x),
                                                      static_cast<std::uint32_t>(y),
                                                      static_cast<std::uint32_t>(z)));
    }
    gi::sort_unique(corner_keys, 3 * (depth + 1));
    phase(1);

    // thesis 5.4.2, eq. 5.1-5.2: density estimate at every corner, gathered from the cells within g.
    struct CornerSum {
        float value[3];
        float normal[3];
        float weight;  ///< sum of kernel x luminance: |normal| / weight says how one-sided it is
    };
    std::vector<CornerSum> sums(corner_keys.size());
    const double edge_scene = bins.edge() * options.render_scale;
    const float norm = static_cast<float>(2.0 / (k_pi * (ge * edge_scene) * (ge * edge_scene)));
    const float inv_g2 = static_cast<float>(1.0 / (ge * ge));
    pre::parallel_chunks(
        corner_keys.size(), 4096, threads, [&](std::size_t begin, std::size_t end, unsigned) {
            for (std::size_t k = begin; k < end; ++k) {
                std::uint32_t q[3];
                gi::demorton3(corner_keys[k], q[0], q[1], q[2]);
                CornerSum s{};
                std::int64_t lo[3], hi[3];
                for (int a = 0; a < 3; ++a) {
                    lo[a] = std::max<std::int64_t>(0, std::int64_t{q[a]} - reach);
                    hi[a] = std::min<std::int64_t>(cells - 1, std::int64_t{q[a]} + reach - 1);
                }
                for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
                    for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
                        for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
                            const std::uint32_t cell = bins.map.find(
                                gi::morton3(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                                            static_cast<std::uint32_t>(z)));
                            if (cell == KeyMap::k_missing) continue;
                            const float ox = static_cast<float>(x - std::int64_t{q[0]});
                            const float oy = static_cast<float>(y - std::int64_t{q[1]});
                            const float oz = static_cast<float>(z - std::int64_t{q[2]});
                            for (std::uint32_t j = bins.cell_begin[cell]; j < bins.cell_begin[cell + 1];
                                 ++j) {
                                const Packed& d = packed[j];
                                const float dx = ox + d.frac[0], dy = oy + d.frac[1], dz = oz + d.frac[2];
                                const float r2 = (dx * dx + dy * dy + dz * dz) * inv_g2;
                                if (!(r2 < 1.0f)) continue;
                                const float w = 1.0f - r2;
                                for (int a = 0; a < 3; ++a) {
                                    s.value[a] += w * d.flux[a];
                                    s.normal[a] += w * d.normal[a];
                                }
                                s.weight += w * d.lum;
                            }
                        }
                for (float& v : s.value) v *= norm;
                sums[k] = s;
            }
        });
    phase(2);
    KeyMap corner_map(corner_keys.size());
    for (std::size_t k = 0; k < corner_keys.size(); ++k)
        corner_map.insert(corner_keys[k], static_cast<std::uint32_t>(k));

    // Leaves: every cell with a non-zero corner.
    std::vector<std::uint64_t> leaf_keys;
    for (std::size_t k = 0; k < corner_keys.size(); ++k) {
        if (!(sums[k].value[0] > 0.0f || sums[k].value[1] > 0.0f || sums[k].value[2] > 0.0f)) continue;
        std::uint32_t q[3];
        gi::demorton3(corner_keys[k], q[0], q[1], q[2]);
        for (std::uint32_t c = 0; c < 8; ++c) {
            std::int64_t v[3];
            bool inside = true;
            for (int a = 0; a < 3; ++a) {
                v[a] = std::int64_t{q[a]} - static_cast<std::int64_t>((c >> a) & 1u);
                inside = inside && v[a] >= 0 && v[a] < cells;
            }
            if (inside)
                leaf_keys.push_back(gi::morton3(static_cast<std::uint32_t>(v[0]),
                                                static_cast<std::uint32_t>(v[1]),
                                                static_cast<std::uint32_t>(v[2])));
        }
    }
    gi::sort_unique(leaf_keys, 3 * depth);
    std::vector<LeafValues> leaves(leaf_keys.size());
    pre::parallel_chunks(leaf_keys.size(), 4096, threads, [&](std::size_t begin, std::size_t end, unsigned) {
        for (std::size_t i = begin; i < end; ++i) {
            LeafValues& lv = leaves[i];
            lv.key = leaf_keys[i];
            std::uint32_t c0[3];
            gi::demorton3(lv.key, c0[0], c0[1], c0[2]);
            double n[3] = {0, 0, 0}, w = 0;
            for (std::uint32_t c = 0; c < 8; ++c) {
                const std::uint32_t k = corner_map.find(
                    gi::morton3(c0[0] + (c & 1u), c0[1] + ((c >> 1) & 1u), c0[2] + ((c >> 2) & 1u)));
                for (int a = 0; a < 3; ++a)
                    lv.corner[c][a] = k == KeyMap::k_missing ? 0.0f : sums[k].value[a];
                if (k == KeyMap::k_missing) continue;
                for (int a = 0; a < 3; ++a) n[a] += sums[k].normal[a];
                w += sums[k].weight;
            }
            const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            // One-sided when the weighted normals mostly agree: |sum w n| >= w / 2.
            for (int a = 0; a < 3; ++a)
                lv.normal[a] = (w > 0 && len >= 0.5 * w) ? static_cast<float>(n[a] / len) : 0.0f;
        }
    });
    phase(3);
    GiOctree tree = gi::build_octree(leaves, root_min, root_size, depth);
    phase(4);
    tree.info.gather_radius = static_cast<float>(ge * bins.edge());
    tree.info.cos_threshold = options.cos_threshold;
    tree.info.sample_count = deposits.size();
    return tree;
}

}  // namespace prt::photons
