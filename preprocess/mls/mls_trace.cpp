// PointRT: batches of rays against the MLS surface on the CPU (see mls_trace.h).
#include "mls_trace.h"

#include <mutex>

#include "prt/parallel.h"
#include "prt/tool_util.h"

namespace prt::mls {

namespace {

constexpr std::size_t k_chunk = 256;  ///< rays per work item: neighbouring pixels share cache lines

template <class Real>
void trace_range(const core::MlsView& view, std::span<const core::Ray> rays, const core::MlsParams& params,
                 std::size_t begin, std::size_t end, TraceResult& out, core::MlsStats& stats) {
    for (std::size_t i = begin; i < end; ++i) {
        const core::Ray& r = rays[i];
        core::MlsHit hit;
        out.found[i] =
            core::trace_mls<Real>(view, r.origin, r.dir, r.t_max, core::ray_inside(r), params, hit, stats)
                ? 1
                : 0;
        out.hits[i] = hit;
    }
}

}  // namespace

core::MlsParams reference_params() {
    core::MlsParams p;
    p.samples = 16;
    p.refine_steps = 12;
    p.faces = core::k_mls_faces_both;
    return p;
}

void TraceTotals::add(const core::MlsStats& s) {
    traversal_steps += s.traversal_steps;
    cells += s.cells;
    intersections += s.intersections;
    splats += s.splats;
    evaluations += s.evaluations;
    truncated += s.truncated;
}

TraceResult trace_rays(const core::MlsView& view, std::span<const core::Ray> rays,
                       const core::MlsParams& params, unsigned threads, Precision precision) {
    TraceResult out;
    out.hits.resize(rays.size());
    out.found.assign(rays.size(), 0);
    std::mutex mutex;
    const double t0 = tool::now_seconds();
    parallel_chunks(rays.size(), k_chunk, resolve_threads(threads),
                    [&](std::size_t begin, std::size_t end, unsigned) {
                        core::MlsStats stats;
                        if (precision == Precision::dual)
                            trace_range<double>(view, rays, params, begin, end, out, stats);
                        else
                            trace_range<float>(view, rays, params, begin, end, out, stats);
                        std::lock_guard<std::mutex> lock(mutex);
                        out.totals.add(stats);
                    });
    out.totals.seconds = tool::now_seconds() - t0;
    out.totals.rays = rays.size();
    for (const std::uint8_t f : out.found) out.totals.hits += f;
    return out;
}

std::vector<std::uint8_t> occluded_rays(const core::MlsView& view, std::span<const core::Ray> rays,
                                        const core::MlsParams& params, unsigned threads, TraceTotals* totals,
                                        Precision precision) {
    std::vector<std::uint8_t> out(rays.size(), 0);
    TraceTotals sum;
    std::mutex mutex;
    const double t0 = tool::now_seconds();
    parallel_chunks(
        rays.size(), k_chunk, resolve_threads(threads), [&](std::size_t begin, std::size_t end, unsigned) {
            core::MlsStats stats;
            for (std::size_t i = begin; i < end; ++i) {
                const core::Ray& r = rays[i];
                const bool inside = core::ray_inside(r);
                out[i] =
                    (precision == Precision::dual
                         ? core::mls_occluded<double>(view, r.origin, r.dir, r.t_max, inside, params, stats)
                         : core::mls_occluded<float>(view, r.origin, r.dir, r.t_max, inside, params, stats))
                        ? 1
                        : 0;
            }
            std::lock_guard<std::mutex> lock(mutex);
            sum.add(stats);
        });
    sum.seconds = tool::now_seconds() - t0;
    sum.rays = rays.size();
    for (const std::uint8_t o : out) sum.hits += o;
    if (totals) *totals = sum;
    return out;
}

}  // namespace prt::mls
