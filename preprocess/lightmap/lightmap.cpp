// PointRT prt-lightmap: sample selection, path tracing on the CPU or the GPU, and the light-map octree
// (thesis 5.3).
#include "lightmap.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "photons.h"
#include "prt/error.h"
#include "prt/parallel.h"
#include "prt/tool_util.h"

#if defined(PRT_HAVE_CUDA)
#include "prt/cuda/lightmap_cuda.h"
#endif

namespace prt::lightmap {

namespace {

/// A sample moved onto its model's traced surface: render-frame hit and side, back into the local frame.
void settle(const core::ModelView& mv, core::Vec3 position, core::Vec3 side, Sample& s) {
    const core::Vec3 lp = core::mul_transpose(mv.rotation, position - mv.offset) * mv.inv_scale;
    const core::Vec3 ln = core::normalize(core::mul_transpose(mv.rotation, side));
    s.render_position = position;
    s.render_normal = side;
    s.position[0] = lp.x;
    s.position[1] = lp.y;
    s.position[2] = lp.z;
    s.normal[0] = ln.x;
    s.normal[1] = ln.y;
    s.normal[2] = ln.z;
}

core::LightMapSampleIn sample_in(const Sample& s) {
    return core::LightMapSampleIn{s.render_position, s.render_normal, s.model, s.settle_reach};
}

void apply(const core::SceneView& scene, const core::LightMapSampleOut& o, Sample& s) {
    s.settled = o.settled != 0;
    if (!s.settled) return;
    if (s.settle_reach > 0.0f) settle(scene.models[s.model], o.position, o.side, s);
    s.irradiance[0] = o.irradiance.x;
    s.irradiance[1] = o.irradiance.y;
    s.irradiance[2] = o.irradiance.z;
}

}  // namespace

std::vector<Sample> select_samples(const gi::SurfacePoints& points, std::uint32_t model_index,
                                   const core::ModelView& model, const double root_min[3], double root_size,
                                   std::uint32_t depth, std::uint32_t per_leaf, float settle_reach) {
    const gi::CellBins bins = gi::bin_points(points.position.size(), root_min, root_size, depth,
                                             [&](std::size_t i) { return &points.position[i].x; });
    std::vector<Sample> out;
    for (std::size_t c = 0; c + 1 < bins.cell_begin.size(); ++c) {
        const std::uint32_t b = bins.cell_begin[c], e = bins.cell_begin[c + 1];
        const std::uint32_t n = e - b, take = std::min(n, per_leaf);
        for (std::uint32_t k = 0; k < take; ++k) {
            const std::uint32_t i = bins.order[b + static_cast<std::uint32_t>((std::uint64_t(k) * n) / take)];
            const core::Vec3 p = points.position[i];
            const core::Vec3 nn = core::normalize_or(points.normal[i], core::Vec3{0, 0, 0});
            if (core::length2(nn) == 0.0f || !core::is_finite(p)) continue;
            Sample s;
            s.position[0] = p.x;
            s.position[1] = p.y;
            s.position[2] = p.z;
            s.normal[0] = nn.x;
            s.normal[1] = nn.y;
            s.normal[2] = nn.z;
            s.render_position = model.rotation * (p * model.scale) + model.offset;
            s.render_normal = core::normalize(model.rotation * nn);
            s.model = model_index;
            s.settle_reach = settle_reach * model.scale;
            out.push_back(s);
        }
    }
    return out;
}

float settle_reach(core::SurfaceKind surface, const gi::SurfacePoints& points, double cell_edge) {
    if (surface == core::SurfaceKind::splats) return 0.0f;
    return static_cast<float>(points.on_surface ? 0.01 * cell_edge : cell_edge);
}

std::size_t drop_unsettled(std::vector<Sample>& samples) {
    const std::size_t before = samples.size();
    std::erase_if(samples, [](const Sample& s) { return !s.settled; });
    return before - samples.size();
}

TraceReport trace_samples(const core::SceneView& scene, const TraceParams& params, std::span<Sample> samples,
                          std::uint64_t first_index, unsigned threads,
                          const std::function<void(std::uint64_t)>& progress, const std::string& backend) {
    TraceReport report;
    const double t0 = tool::now_seconds();
    if (photons::resolve_backend(backend) == "cuda") {
#if defined(PRT_HAVE_CUDA)
        std::vector<core::LightMapSampleIn> in(samples.size());
        for (std::size_t i = 0; i < samples.size(); ++i) in[i] = sample_in(samples[i]);
        std::vector<core::LightMapSampleOut> out(samples.size());
        const cuda::LightMapCudaResult r =
            cuda::trace_light_map_cuda(scene, params, in, first_index, out, progress);
        for (std::size_t i = 0; i < samples.size(); ++i) apply(scene, out[i], samples[i]);
        report.backend = r.device;
        report.kernel_seconds = r.kernel_seconds;
        return report;
#endif
    }
    const unsigned workers = resolve_threads(threads);
    std::atomic<std::uint64_t> done{0};
    parallel_chunks(samples.size(), 64, workers, [&](std::size_t begin, std::size_t end, unsigned worker) {
        core::RayCounters c;
        for (std::size_t i = begin; i < end; ++i) {
            Sample& s = samples[i];
            apply(scene, core::trace_light_map_sample(scene, params, sample_in(s), first_index + i, c), s);
        }
        const std::uint64_t d = done.fetch_add(end - begin) + (end - begin);
        if (worker == 0 && progress) progress(d);
    });
    report.backend = "cpu (" + std::to_string(workers) + " threads)";
    report.kernel_seconds = tool::now_seconds() - t0;
    return report;
}

gi::GiOctree build_light_map_octree(std::span<const Sample> samples, const double root_min[3],
                                    double root_size, const GatherOptions& options) {
    const std::uint32_t depth = options.depth;
    if (depth > pool::k_max_gi_depth)
        throw Error("light-map depth " + std::to_string(depth) + " above " +
                    std::to_string(pool::k_max_gi_depth));
    const gi::CellBins bins = gi::bin_points(samples.size(), root_min, root_size, depth,
                                             [&](std::size_t i) { return samples[i].position; });
    const double g = options.radius_edges;
    const std::int64_t reach = static_cast<std::int64_t>(std::ceil(g));
    const std::int64_t cells = std::int64_t{1} << depth;
    // Candidate leaves: cells holding a sample and their 26 neighbours (a splat reaches past the
    // cell of its centre).
    std::vector<std::uint64_t> keys;
    keys.reserve(bins.cell_keys.size() * 27);
    for (std::uint64_t key : bins.cell_keys) {
        std::uint32_t c[3];
        pre::demorton3(key, c[0], c[1], c[2]);
        for (std::int64_t z = std::int64_t{c[2]} - 1; z <= std::int64_t{c[2]} + 1; ++z)
            for (std::int64_t y = std::int64_t{c[1]} - 1; y <= std::int64_t{c[1]} + 1; ++y)
                for (std::int64_t x = std::int64_t{c[0]} - 1; x <= std::int64_t{c[0]} + 1; ++x)
                    if (x >= 0 && y >= 0 && z >= 0 && x < cells && y < cells && z < cells)
                        keys.push_back(pre::morton3(static_cast<std::uint32_t>(x),
                                                    static_cast<std::uint32_t>(y),
                                                    static_cast<std::uint32_t>(z)));
    }
    gi::sort_unique(keys, 3 * depth);
    std::vector<gi::LeafValues> leaves(keys.size());
    std::vector<std::uint8_t> keep(keys.size(), 0);
    parallel_chunks(
        keys.size(), 1024, resolve_threads(options.threads),
        [&](std::size_t begin, std::size_t end, unsigned) {
            std::vector<std::uint32_t> near;
            for (std::size_t li = begin; li < end; ++li) {
                std::uint32_t c[3];
                pre::demorton3(keys[li], c[0], c[1], c[2]);
                near.clear();
                for (std::int64_t z = std::int64_t{c[2]} - reach; z <= std::int64_t{c[2]} + reach; ++z)
                    for (std::int64_t y = std::int64_t{c[1]} - reach; y <= std::int64_t{c[1]} + reach; ++y)
                        for (std::int64_t x = std::int64_t{c[0]} - reach; x <= std::int64_t{c[0]} + reach;
                             ++x) {
                            if (x < 0 || y < 0 || z < 0 || x >= cells || y >= cells || z >= cells) continue;
                            const std::uint32_t cell = bins.map.find(
                                pre::morton3(static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y),
                                             static_cast<std::uint32_t>(z)));
                            if (cell == gi::KeyMap::k_missing) continue;
                            for (std::uint32_t j = bins.cell_begin[cell]; j < bins.cell_begin[cell + 1]; ++j)
                                near.push_back(bins.order[j]);
                        }
                // The leaf's normal: its own samples, else those within g of its centre.
                double n[3] = {0, 0, 0};
                for (int pass = 0; pass < 2 && n[0] == 0 && n[1] == 0 && n[2] == 0; ++pass) {
                    for (std::uint32_t i : near) {
                        double q[3];
                        bins.grid(samples[i].position, q);
                        double d2 = 0;
                        bool inside = true;
                        for (int a = 0; a < 3; ++a) {
                            const double v = q[a] - (c[a] + 0.5);
                            d2 += v * v;
                            inside = inside && std::floor(q[a]) == c[a];
                        }
                        if (pass == 0 ? !inside : !(d2 < g * g)) continue;
                        for (int a = 0; a < 3; ++a) n[a] += samples[i].normal[a];
                    }
                }
                const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                if (!(len > 1e-6)) continue;
                gi::LeafValues& lv = leaves[li];
                lv.key = keys[li];
                for (int a = 0; a < 3; ++a) lv.normal[a] = static_cast<float>(n[a] / len);
                // eq. 5.3-5.4 at each corner.
                bool valid[8];
                int valid_count = 0;
                for (std::uint32_t k = 0; k < 8; ++k) {
                    const double qc[3] = {double(c[0] + (k & 1u)), double(c[1] + ((k >> 1) & 1u)),
                                          double(c[2] + ((k >> 2) & 1u))};
                    double sum[3] = {0, 0, 0}, wsum = 0;
                    for (std::uint32_t i : near) {
                        const Sample& s = samples[i];
                        const double cosn = s.normal[0] * lv.normal[0] + s.normal[1] * lv.normal[1] +
                                            s.normal[2] * lv.normal[2];
                        if (cosn < options.reject_cos) continue;
                        double q[3];
                        bins.grid(s.position, q);
                        const double dist =
                            std::sqrt((q[0] - qc[0]) * (q[0] - qc[0]) + (q[1] - qc[1]) * (q[1] - qc[1]) +
                                      (q[2] - qc[2]) * (q[2] - qc[2]));
                        if (!(dist < g)) continue;
                        const double y = (1.0 - dist / g) * (1.0 - dist / g);
                        for (int a = 0; a < 3; ++a) sum[a] += y * s.irradiance[a];
                        wsum += y;
                    }
                    valid[k] = wsum > 0;
                    for (int a = 0; a < 3; ++a)
                        lv.corner[k][a] = valid[k] ? static_cast<float>(sum[a] / wsum) : 0.0f;
                    valid_count += valid[k] ? 1 : 0;
                }
                if (valid_count == 0) continue;
                float mean[3] = {0, 0, 0};
                for (std::uint32_t k = 0; k < 8; ++k)
                    if (valid[k])
                        for (int a = 0; a < 3; ++a)
                            mean[a] += lv.corner[k][a] / static_cast<float>(valid_count);
                for (std::uint32_t k = 0; k < 8; ++k)
                    if (!valid[k])
                        for (int a = 0; a < 3; ++a) lv.corner[k][a] = mean[a];
                keep[li] = 1;
            }
        });
    std::vector<gi::LeafValues> kept;
    kept.reserve(leaves.size());
    for (std::size_t i = 0; i < leaves.size(); ++i)
        if (keep[i]) kept.push_back(leaves[i]);
    gi::GiOctree tree = gi::build_octree(kept, root_min, root_size, depth);
    tree.info.gather_radius = static_cast<float>(g * bins.edge());
    tree.info.cos_threshold = options.lookup_cos;
    tree.info.sample_count = samples.size();
    double mean = 0, max = 0;
    for (const gi::LeafValues& lv : kept)
        for (const auto& cv : lv.corner) {
            const double l = 0.2126 * cv[0] + 0.7152 * cv[1] + 0.0722 * cv[2];
            mean += l;
            max = std::max(max, l);
        }
    tree.info.total[0] = kept.empty() ? 0.0f : static_cast<float>(mean / (8.0 * kept.size()));
    tree.info.total[1] = static_cast<float>(max);
    return tree;
}

}  // namespace prt::lightmap
