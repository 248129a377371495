// PointRT CUDA: prt-radii's exact k-nearest-neighbour radii on the GPU (prt/cuda/knn_cuda.h; thesis
// 3.1: a splat's radius is the distance to its k-th nearest neighbour).
//
// The points are sorted along a 63-bit Morton curve (cub's radix sort), cut into leaves of 32
// consecutive points, and a complete binary tree of boxes is built over the leaves (heap order:
// node i has children 2i and 2i + 1; each node bounds a contiguous range of the curve, as in a
// linear BVH, Lauterbach et al. 2009, "Fast BVH construction on GPUs"). One thread answers one
// query, in curve order, and a warp's 32 queries (curve neighbours) walk the tree together: depth
// first, the child nearer to most of them first, a subtree skipped when its box is farther than
// every query's k-th candidate (Friedman, Bentley & Finkel 1977, the CPU kd-tree's rule, for each
// query; the squared distance to a box as in Arya & Mount 1993). A walk of its own per thread was
// 3.4x slower (100M points, H200): its warps diverged at every node. The k candidates live in
// registers, sorted by (squared distance, index), with k_max - k sentinels in front so that the
// k-th is always the last slot.
//
// Exact and equal to the CPU's (common/kd_tree.h): squared distances in float as ((dx * dx + dy *
// dy) + dz * dz) with d = point - query, written with the _rn intrinsics (and the file built with
// --fmad=false) so nothing is fused; a box's squared distance is computed from its float corners
// in the same order, so it is never above the distance of a point inside it (rounding is
// monotone), and a box is skipped only when strictly farther than the k-th candidate (a point at
// the same distance with a smaller index would still enter). The local clamp needs every raw radius
// before it can take a point's neighbours' median: the search stores each point's k neighbours
// (4k bytes a point, in curve order) where the device has that memory free, and a clamp kernel reads
// them; otherwise a second search finds them again (the same neighbours: the search is exact).
#include <cuda_runtime.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <cub/device/device_radix_sort.cuh>
#include <limits>
#include <type_traits>
#include <vector>

#include "cuda_check.h"
#include "device_buffer.h"
#include "prt/core/morton.h"
#include "prt/cuda/device.h"
#include "prt/cuda/knn_cuda.h"

namespace prt::cuda {

namespace {

constexpr std::uint32_t k_leaf = 32;   ///< points per leaf of the search tree: one per lane of a warp
constexpr std::uint32_t k_stack = 32;  ///< n < 2^32: at most 2^27 leaves, a depth of 27
constexpr unsigned k_block = 128;
constexpr std::uint64_t k_queries_per_launch = std::uint64_t{1} << 22;  ///< progress between launches
/// Device memory left free beside the local clamp's stored neighbours (the medians' sorts and cub's
/// temporary storage come after the search, from what it frees).
constexpr std::uint64_t k_neighbour_margin = std::uint64_t{256} << 20;

double now_seconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Floats mapped to unsigned integers of the same order (for atomicMin / atomicMax).
__host__ __device__ inline std::uint32_t order_key(std::uint32_t u) {
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}
float from_order_key(std::uint32_t key) {
    const std::uint32_t u = (key & 0x80000000u) ? (key & 0x7fffffffu) : ~key;
    float f;
    std::memcpy(&f, &u, sizeof f);
    return f;
}

/// Bounds of the finite points and the first non-finite one.
__global__ void bounds_kernel(const float* xyz, std::uint64_t n, std::uint32_t* bounds,
                              unsigned long long* first_bad) {
    float lo[3], hi[3];
    for (int a = 0; a < 3; ++a) lo[a] = INFINITY, hi[a] = -INFINITY;
    unsigned long long bad = ~0ull;
    const std::uint64_t stride = std::uint64_t(gridDim.x) * blockDim.x;
    for (std::uint64_t i = std::uint64_t(blockIdx.x) * blockDim.x + threadIdx.x; i < n; i += stride)
        for (int a = 0; a < 3; ++a) {
            const float v = xyz[3 * i + a];
            if (!isfinite(v))
                bad = min(bad, static_cast<unsigned long long>(i));
            else
                lo[a] = fminf(lo[a], v), hi[a] = fmaxf(hi[a], v);
        }
    for (int o = 16; o > 0; o >>= 1) {
        for (int a = 0; a < 3; ++a) {
            lo[a] = fminf(lo[a], __shfl_xor_sync(0xffffffffu, lo[a], o));
            hi[a] = fmaxf(hi[a], __shfl_xor_sync(0xffffffffu, hi[a], o));
        }
        bad = min(bad, __shfl_xor_sync(0xffffffffu, bad, o));
    }
    if ((threadIdx.x & 31) == 0) {
        for (int a = 0; a < 3; ++a) {
            atomicMin(&bounds[a], order_key(__float_as_uint(lo[a])));
            atomicMax(&bounds[3 + a], order_key(__float_as_uint(hi[a])));
        }
        if (bad != ~0ull) atomicMin(first_bad, bad);
    }
}

__global__ void morton_kernel(const float* xyz, std::uint64_t n, float3 lo, float scale, std::uint64_t* keys,
                              std::uint32_t* values) {
    const std::uint64_t i = std::uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const float o[3] = {lo.x, lo.y, lo.z};
    std::uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
        const float c = fminf(fmaxf((xyz[3 * i + a] - o[a]) * scale, 0.0f), 2097151.0f);
        key |= core::spread_bits21(static_cast<std::uint32_t>(c)) << a;
    }
    keys[i] = key;
    values[i] = static_cast<std::uint32_t>(i);
}

/// The sorted points: x, y, z and the point's index (its bits in w).
__global__ void gather_kernel(const float* xyz, const std::uint32_t* order, std::uint64_t n, float4* pts) {
    const std::uint64_t s = std::uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (s >= n) return;
    const std::uint32_t i = order[s];
    pts[s] = make_float4(xyz[3 * std::uint64_t(i)], xyz[3 * std::uint64_t(i) + 1],
                         xyz[3 * std::uint64_t(i) + 2], __uint_as_float(i));
}

/// Leaf boxes (nodes first_leaf + l); leaves past the points get empty boxes (lo > hi).
__global__ void leaf_box_kernel(const float4* pts, std::uint64_t n, std::uint32_t first_leaf, float4* lo,
                                float4* hi) {
    const std::uint32_t l = blockIdx.x * blockDim.x + threadIdx.x;
    if (l >= first_leaf) return;
    float4 a = make_float4(INFINITY, INFINITY, INFINITY, 0),
           b = make_float4(-INFINITY, -INFINITY, -INFINITY, 0);
    const std::uint64_t begin = std::uint64_t(l) * k_leaf, end = min(n, begin + k_leaf);
    for (std::uint64_t p = begin; p < end; ++p) {
        const float4 c = pts[p];
        a.x = fminf(a.x, c.x), a.y = fminf(a.y, c.y), a.z = fminf(a.z, c.z);
        b.x = fmaxf(b.x, c.x), b.y = fmaxf(b.y, c.y), b.z = fmaxf(b.z, c.z);
    }
    lo[first_leaf + l] = a;
    hi[first_leaf + l] = b;
}

/// Inner nodes [first, 2 first): the union of their children.
__global__ void inner_box_kernel(std::uint32_t first, float4* lo, float4* hi) {
    const std::uint32_t i = first + blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= 2 * first) return;
    const float4 a0 = lo[2 * i], a1 = lo[2 * i + 1], b0 = hi[2 * i], b1 = hi[2 * i + 1];
    lo[i] = make_float4(fminf(a0.x, a1.x), fminf(a0.y, a1.y), fminf(a0.z, a1.z), 0);
    hi[i] = make_float4(fmaxf(b0.x, b1.x), fmaxf(b0.y, b1.y), fmaxf(b0.z, b1.z), 0);
}

/// The CPU's squared distance, unfused: ((dx * dx + dy * dy) + dz * dz), d = point - query.
__device__ __forceinline__ float distance2(const float4 p, const float4 q) {
    const float dx = __fsub_rn(p.x, q.x), dy = __fsub_rn(p.y, q.y), dz = __fsub_rn(p.z, q.z);
    return __fadd_rn(__fadd_rn(__fmul_rn(dx, dx), __fmul_rn(dy, dy)), __fmul_rn(dz, dz));
}

/// A lower bound of distance2(p, q) for every p in the box, in the same float operations.
__device__ __forceinline__ float box_distance2(const float4 lo, const float4 hi, const float4 q) {
    const float ax = fmaxf(fmaxf(__fsub_rn(lo.x, q.x), __fsub_rn(q.x, hi.x)), 0.0f);
    const float ay = fmaxf(fmaxf(__fsub_rn(lo.y, q.y), __fsub_rn(q.y, hi.y)), 0.0f);
    const float az = fmaxf(fmaxf(__fsub_rn(lo.z, q.z), __fsub_rn(q.z, hi.z)), 0.0f);
    return __fadd_rn(__fadd_rn(__fmul_rn(ax, ax), __fmul_rn(ay, ay)), __fmul_rn(az, az));
}

/// The CPU's candidate order (KdTree::Best): nearer first, then the smaller index.
__device__ __forceinline__ bool before(float da, std::uint32_t ia, float db, std::uint32_t ib) {
    return da < db || (da == db && ia < ib);
}

/// radii.cpp clamp_radii_local for point qi: m = the (k / 2)-th smallest raw radius of its k
/// neighbours (0-based, nth_element's; `v` holds them in its last k slots, the first KMAX - k are
/// -inf), limit = factor * m; out[qi] the clamped radius, the clamped counted (a ballot of the lanes
/// active here).
template <int KMAX>
__device__ __forceinline__ void clamp_local(const float (&v)[KMAX], std::uint32_t k, std::uint32_t qi,
                                            const float* raw, float factor, float* out,
                                            unsigned long long* clamped) {
    const int target = KMAX - int(k) + int(k / 2);  // the sentinels rank first
    float m = 0;
#pragma unroll
    for (int j = 0; j < KMAX; ++j) {
        int less = 0, equal_or_less = 0;
#pragma unroll
        for (int i = 0; i < KMAX; ++i) less += v[i] < v[j], equal_or_less += v[i] <= v[j];
        if (less <= target && target < equal_or_less) m = v[j];
    }
    const float limit = __fmul_rn(factor, m);
    const float self = raw[qi];
    const bool clamp = self > limit;
    out[qi] = clamp ? limit : self;
    const unsigned ballot = __ballot_sync(__activemask(), clamp);
    if (ballot && (threadIdx.x & 31) == __ffs(__activemask()) - 1)
        atomicAdd(clamped, static_cast<unsigned long long>(__popc(ballot)));
}

/// One query per thread, points [first, first + count) of the curve, a warp's 32 queries walking
/// the tree together: a node is entered when any of them needs it (its box no farther than that
/// query's k-th candidate), so the warp never diverges in the walk, a leaf's 32 points are one
/// coalesced load, each handed to every lane by shuffles. A query sees every node it would see
/// alone (and some more), so the result is the same. Pass 1 (CLAMP false) writes the raw radius
/// and, with `neighbours`, the query's k neighbours at [(first + t) k, (first + t + 1) k) (curve
/// order, nearest first); pass 2 (CLAMP true, every raw radius known) the locally clamped radius,
/// counting the clamped.
template <int KMAX, bool CLAMP>
__global__ void __launch_bounds__(k_block)
    knn_kernel(const float4* __restrict__ pts, const float4* __restrict__ lo, const float4* __restrict__ hi,
               std::uint32_t first_leaf, std::uint64_t n, std::uint32_t k, std::uint64_t first,
               std::uint64_t count, float* raw, float factor, float* out, unsigned long long* clamped,
               std::uint32_t* neighbours) {
    constexpr unsigned all = 0xffffffffu;
    const std::uint64_t t = std::uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
    const bool active = t < count;
    if (__all_sync(all, !active)) return;  // whole warps only: every lane takes part in the votes
    const unsigned lane = threadIdx.x & 31;
    const float4 q = active ? pts[first + t] : make_float4(0, 0, 0, __uint_as_float(0xffffffffu));
    const std::uint32_t qi = __float_as_uint(q.w);

    float bd[KMAX];
    std::uint32_t bi[KMAX];
#pragma unroll
    for (int j = 0; j < KMAX; ++j) {
        bd[j] = j < KMAX - int(k) ? -1.0f : INFINITY;  // sentinels first: slot KMAX - 1 is the k-th
        bi[j] = 0xffffffffu;
    }
    if (!active) bd[KMAX - 1] = -INFINITY;  // needs no node, takes no point

    std::uint32_t stack[k_stack];  // warp-uniform
    int sp = 0;
    std::uint32_t node = 1;
    for (;;) {
        if (node >= first_leaf) {
            const std::uint64_t b = std::uint64_t(node - first_leaf) * k_leaf;
            const int m = b < n ? int(min(std::uint64_t(k_leaf), n - b)) : 0;
            const float4 own = lane < unsigned(m) ? pts[b + lane] : make_float4(0, 0, 0, 0);
            for (int j = 0; j < m; ++j) {
                float4 c;
                c.x = __shfl_sync(all, own.x, j);
                c.y = __shfl_sync(all, own.y, j);
                c.z = __shfl_sync(all, own.z, j);
                c.w = __shfl_sync(all, own.w, j);
                const std::uint32_t ci = __float_as_uint(c.w);
                const float d = distance2(c, q);
                if (ci == qi || !before(d, ci, bd[KMAX - 1], bi[KMAX - 1])) continue;
                bd[KMAX - 1] = d;
                bi[KMAX - 1] = ci;
#pragma unroll
                for (int i = KMAX - 1; i > 0; --i)
                    if (before(bd[i], bi[i], bd[i - 1], bi[i - 1])) {
                        const float td = bd[i];
                        bd[i] = bd[i - 1], bd[i - 1] = td;
                        const std::uint32_t ti = bi[i];
                        bi[i] = bi[i - 1], bi[i - 1] = ti;
                    }
            }
        } else {
            const std::uint32_t c0 = 2 * node, c1 = c0 + 1;
            const float d0 = box_distance2(lo[c0], hi[c0], q), d1 = box_distance2(lo[c1], hi[c1], q);
            const float worst = bd[KMAX - 1];
            const bool need0 = __any_sync(all, d0 <= worst), need1 = __any_sync(all, d1 <= worst);
            if (need0 || need1) {
                // nearer first for most of the warp's queries
                const unsigned votes = __popc(__ballot_sync(all, active && d0 <= d1));
                const unsigned voters = __popc(__ballot_sync(all, active));
                const bool zero_first = need0 && (!need1 || 2 * votes >= voters);
                if (need0 && need1) stack[sp++] = zero_first ? c1 : c0;
                node = zero_first ? c0 : c1;
                continue;
            }
        }
        bool next = false;
        while (sp > 0) {
            const std::uint32_t candidate = stack[--sp];
            const float d = box_distance2(lo[candidate], hi[candidate], q);
            if (__any_sync(all, d <= bd[KMAX - 1])) {
                node = candidate;
                next = true;
                break;
            }
        }
        if (!next) break;
    }
    if (!active) return;

    if constexpr (!CLAMP) {
        raw[qi] = __fsqrt_rn(bd[KMAX - 1]);  // n > k: k others are always found
        if (neighbours != nullptr) {
            std::uint32_t* own = neighbours + (first + t) * k;
#pragma unroll
            for (int j = 0; j < KMAX; ++j)
                if (j >= KMAX - int(k)) own[j - (KMAX - int(k))] = bi[j];
        }
    } else {
        float v[KMAX];
#pragma unroll
        for (int j = 0; j < KMAX; ++j) v[j] = j < KMAX - int(k) ? -INFINITY : raw[bi[j]];
        clamp_local<KMAX>(v, k, qi, raw, factor, out, clamped);
    }
}

/// The local clamp from the neighbours pass 1 stored (knn_kernel): curve point s's radius, as
/// pass 2 would clamp it.
template <int KMAX>
__global__ void stored_clamp_kernel(const float4* __restrict__ pts,
                                    const std::uint32_t* __restrict__ neighbours, std::uint64_t n,
                                    std::uint32_t k, const float* raw, float factor, float* out,
                                    unsigned long long* clamped) {
    const std::uint64_t s = std::uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (s >= n) return;
    const std::uint32_t qi = __float_as_uint(pts[s].w);
    const std::uint32_t* own = neighbours + s * k;
    float v[KMAX];
#pragma unroll
    for (int j = 0; j < KMAX; ++j) v[j] = j < KMAX - int(k) ? -INFINITY : raw[own[j - (KMAX - int(k))]];
    clamp_local<KMAX>(v, k, qi, raw, factor, out, clamped);
}

/// radii.cpp clamp_radii with the global limit.
__global__ void global_clamp_kernel(const float* raw, std::uint64_t n, float limit, float* out,
                                    unsigned long long* clamped) {
    const std::uint64_t i = std::uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const bool clamp = raw[i] > limit;
    out[i] = clamp ? limit : raw[i];
    const unsigned ballot = __ballot_sync(__activemask(), clamp);
    if (ballot && (threadIdx.x & 31) == __ffs(__activemask()) - 1)
        atomicAdd(clamped, static_cast<unsigned long long>(__popc(ballot)));
}

/// radii.cpp's median: the middle element, or the mean of the two middle ones in double.
double median(const DeviceBuffer<float>& values, std::uint64_t n) {
    DeviceBuffer<float> sorted(n);
    std::size_t temp_bytes = 0;
    PRT_CUDA_CHECK(cub::DeviceRadixSort::SortKeys(nullptr, temp_bytes, values.data(), sorted.data(),
                                                  static_cast<std::int64_t>(n)));
    DeviceBuffer<unsigned char> temp(std::max<std::size_t>(temp_bytes, 1));
    PRT_CUDA_CHECK(cub::DeviceRadixSort::SortKeys(temp.data(), temp_bytes, values.data(), sorted.data(),
                                                  static_cast<std::int64_t>(n)));
    const std::uint64_t mid = (n - 1) / 2;
    float m[2] = {0, 0};
    sorted.download(m, n % 2 == 0 ? 2 : 1, mid);
    PRT_CUDA_CHECK(cudaDeviceSynchronize());
    double r = m[0];
    if (n % 2 == 0) r = 0.5 * (r + m[1]);
    return r;
}

template <int KMAX>
void run_search(const DeviceBuffer<float4>& pts, const DeviceBuffer<float4>& lo,
                const DeviceBuffer<float4>& hi, std::uint32_t first_leaf, std::uint64_t n, std::uint32_t k,
                bool clamp_pass, DeviceBuffer<float>& raw, float factor, DeviceBuffer<float>& out,
                DeviceBuffer<unsigned long long>& clamped, std::uint32_t* neighbours,
                const std::function<void(std::uint64_t)>& progress, std::uint64_t done_before,
                std::uint64_t weight) {
    for (std::uint64_t first = 0; first < n; first += k_queries_per_launch) {
        const std::uint64_t count = std::min(k_queries_per_launch, n - first);
        if (clamp_pass)
            launch_kernel(launch_1d(count, k_block), knn_kernel<KMAX, true>, pts.data(), lo.data(), hi.data(),
                          first_leaf, n, k, first, count, raw.data(), factor, out.data(), clamped.data(),
                          nullptr);
        else
            launch_kernel(launch_1d(count, k_block), knn_kernel<KMAX, false>, pts.data(), lo.data(),
                          hi.data(), first_leaf, n, k, first, count, raw.data(), factor, out.data(),
                          clamped.data(), neighbours);
        PRT_CUDA_CHECK(cudaDeviceSynchronize());
        if (progress) progress(done_before + (first + count) / weight);
    }
}

template <int KMAX>
void run_stored_clamp(const DeviceBuffer<float4>& pts, const DeviceBuffer<std::uint32_t>& neighbours,
                      std::uint64_t n, std::uint32_t k, const DeviceBuffer<float>& raw, float factor,
                      DeviceBuffer<float>& out, DeviceBuffer<unsigned long long>& clamped) {
    launch_kernel(launch_1d(n, 256), stored_clamp_kernel<KMAX>, pts.data(), neighbours.data(), n, k,
                  raw.data(), factor, out.data(), clamped.data());
    PRT_CUDA_CHECK(cudaDeviceSynchronize());
}

/// Calls run(std::integral_constant<int, KMAX>) with the kernels' register width for k: the
/// smallest of 8, 16 and 32 that holds k neighbours (k <= 32 was checked before).
template <class Run>
void with_width(std::uint32_t k, Run&& run) {
    if (k <= 8)
        run(std::integral_constant<int, 8>{});
    else if (k <= 16)
        run(std::integral_constant<int, 16>{});
    else
        run(std::integral_constant<int, 32>{});
}

void search(std::uint32_t k, const DeviceBuffer<float4>& pts, const DeviceBuffer<float4>& lo,
            const DeviceBuffer<float4>& hi, std::uint32_t first_leaf, std::uint64_t n, bool clamp_pass,
            DeviceBuffer<float>& raw, float factor, DeviceBuffer<float>& out,
            DeviceBuffer<unsigned long long>& clamped, std::uint32_t* neighbours,
            const std::function<void(std::uint64_t)>& progress, std::uint64_t done_before,
            std::uint64_t weight) {
    with_width(k, [&](auto width) {
        run_search<decltype(width)::value>(pts, lo, hi, first_leaf, n, k, clamp_pass, raw, factor, out,
                                           clamped, neighbours, progress, done_before, weight);
    });
}

/// The local clamp from the neighbours the search stored (the same radii and count as the second
/// search's).
void stored_clamp(const DeviceBuffer<float4>& pts, const DeviceBuffer<std::uint32_t>& neighbours,
                  std::uint64_t n, std::uint32_t k, const DeviceBuffer<float>& raw, float factor,
                  DeviceBuffer<float>& out, DeviceBuffer<unsigned long long>& clamped) {
    with_width(k, [&](auto width) {
        run_stored_clamp<decltype(width)::value>(pts, neighbours, n, k, raw, factor, out, clamped);
    });
}

std::uint32_t leaf_level(std::uint64_t n) {
    const std::uint64_t leaves = (n + k_leaf - 1) / k_leaf;
    std::uint32_t first = 1;
    while (first < leaves) first <<= 1;
    return first;
}

}  // namespace

std::uint64_t knn_radii_device_bytes(std::uint64_t n) {
    // The Morton sort's peak: positions (12 B), keys and indices double-buffered (24 B), cub's
    // temporary storage (bounded here by 4 B); later phases (16 B sorted points + the tree + 8 B
    // of radii; 8 B of radii + 8 B for a median) stay below it.
    const std::uint64_t tree = 2 * std::uint64_t(leaf_level(n)) * 2 * sizeof(float4);
    return std::max(n * 40, n * 24 + tree) + (std::uint64_t{64} << 20);
}

bool knn_radii_usable(std::uint64_t n, std::uint32_t k, std::string* why) {
    if (k == 0 || k > k_knn_max_k) {
        if (why)
            *why = "k = " + std::to_string(k) + " is above the GPU search's " + std::to_string(k_knn_max_k);
        return false;
    }
    if (n >= 0xffffffffull) {
        if (why) *why = std::to_string(n) + " points: the GPU search indexes at most 2^32 - 2";
        return false;
    }
    if (!device_available(why)) return false;
    std::size_t free = 0, total = 0;
    if (cudaSetDevice(0) != cudaSuccess || cudaMemGetInfo(&free, &total) != cudaSuccess) {
        cudaGetLastError();
        if (why) *why = "cannot query the device's free memory";
        return false;
    }
    const std::uint64_t need = knn_radii_device_bytes(n);
    if (need > free) {
        if (why)
            *why = "the search needs " + std::to_string(need >> 20) + " MiB of device memory, " +
                   std::to_string(free >> 20) + " MiB are free";
        return false;
    }
    return true;
}

KnnRadiiResult knn_radii_cuda(std::span<const float> xyz, std::uint32_t k, KnnClamp clamp, float factor,
                              std::span<float> radii, const std::function<void(std::uint64_t)>& progress,
                              KnnNeighbours neighbour_store) {
    KnnRadiiResult result;
    const std::uint64_t n = xyz.size() / 3;
    if (xyz.size() != 3 * n || radii.size() != n)
        throw Error("knn_radii_cuda: 3n coordinates and n radii expected");
    if (k == 0 || k > k_knn_max_k || n <= k || n >= 0xffffffffull)
        throw Error("knn_radii_cuda: k = " + std::to_string(k) + " and n = " + std::to_string(n) +
                    " outside the GPU search's range");
    PRT_CUDA_CHECK(cudaSetDevice(0));
    double t = now_seconds();

    // Upload, bounds and the first non-finite coordinate.
    DeviceBuffer<float> d_xyz;
    d_xyz.upload(xyz.data(), xyz.size());
    DeviceBuffer<std::uint32_t> d_bounds(6);
    DeviceBuffer<unsigned long long> d_bad(1);
    {
        const std::uint32_t init[6] = {0xffffffffu, 0xffffffffu, 0xffffffffu, 0, 0, 0};
        d_bounds.upload(init, 6);
        PRT_CUDA_CHECK(cudaMemset(d_bad.data(), 0xff, sizeof(unsigned long long)));
    }
    launch_kernel(launch_1d(std::min<std::uint64_t>(n, std::uint64_t{1} << 22), 256), bounds_kernel,
                  d_xyz.data(), n, d_bounds.data(), d_bad.data());
    std::uint32_t bounds[6];
    unsigned long long bad = 0;
    d_bounds.download(bounds, 6);
    d_bad.download(&bad, 1);
    PRT_CUDA_CHECK(cudaDeviceSynchronize());
    result.seconds_upload = now_seconds() - t;
    if (bad != ~0ull) {
        result.non_finite = static_cast<std::int64_t>(bad);
        return result;
    }
    t = now_seconds();

    // Morton order (any order would be exact; this one makes the tree's boxes small and a warp's
    // queries neighbours).
    const float3 lo =
        make_float3(from_order_key(bounds[0]), from_order_key(bounds[1]), from_order_key(bounds[2]));
    const float extent = std::max({from_order_key(bounds[3]) - lo.x, from_order_key(bounds[4]) - lo.y,
                                   from_order_key(bounds[5]) - lo.z});
    const float scale = extent > 0 ? 2097151.0f / extent : 0.0f;
    DeviceBuffer<std::uint32_t> order;
    {
        DeviceBuffer<std::uint64_t> keys(n), keys_alt(n);
        DeviceBuffer<std::uint32_t> values(n), values_alt(n);
        launch_kernel(launch_1d(n, 256), morton_kernel, d_xyz.data(), n, lo, scale, keys.data(),
                      values.data());
        cub::DoubleBuffer<std::uint64_t> kb(keys.data(), keys_alt.data());
        cub::DoubleBuffer<std::uint32_t> vb(values.data(), values_alt.data());
        std::size_t temp_bytes = 0;
        PRT_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(nullptr, temp_bytes, kb, vb,
                                                       static_cast<std::int64_t>(n), 0, 63));
        DeviceBuffer<unsigned char> temp(std::max<std::size_t>(temp_bytes, 1));
        PRT_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(temp.data(), temp_bytes, kb, vb,
                                                       static_cast<std::int64_t>(n), 0, 63));
        order = vb.Current() == values.data() ? std::move(values) : std::move(values_alt);
    }
    DeviceBuffer<float4> pts(n);
    launch_kernel(launch_1d(n, 256), gather_kernel, d_xyz.data(), order.data(), n, pts.data());
    PRT_CUDA_CHECK(cudaDeviceSynchronize());
    d_xyz.release();
    order.release();

    // The tree's boxes, leaves up.
    const std::uint32_t first_leaf = leaf_level(n);
    DeviceBuffer<float4> box_lo(2 * std::size_t(first_leaf)), box_hi(2 * std::size_t(first_leaf));
    launch_kernel(launch_1d(first_leaf, 256), leaf_box_kernel, pts.data(), n, first_leaf, box_lo.data(),
                  box_hi.data());
    for (std::uint32_t level = first_leaf / 2; level >= 1; level /= 2)
        launch_kernel(launch_1d(level, 256), inner_box_kernel, level, box_lo.data(), box_hi.data());
    PRT_CUDA_CHECK(cudaDeviceSynchronize());
    result.seconds_index = now_seconds() - t;
    t = now_seconds();

    // The search: raw radii, then (local clamp) the clamped radii from the neighbours it stored, or
    // from a second search where the device lacks the memory to store them.
    DeviceBuffer<float> raw(n), out;
    DeviceBuffer<unsigned long long> d_clamped(1);
    PRT_CUDA_CHECK(cudaMemset(d_clamped.data(), 0, sizeof(unsigned long long)));
    const bool local = clamp == KnnClamp::local;
    if (local) out.resize(n);
    DeviceBuffer<std::uint32_t> neighbours;
    if (local && neighbour_store == KnnNeighbours::stored_if_free) {
        std::size_t free = 0, total = 0;
        const std::uint64_t bytes = n * k * sizeof(std::uint32_t);
        PRT_CUDA_CHECK(cudaMemGetInfo(&free, &total));
        if (bytes + k_neighbour_margin <= free) neighbours.resize(n * k);
    }
    result.neighbours_stored = neighbours.size() > 0;
    const std::uint64_t weight = local && !result.neighbours_stored ? 2 : 1;
    search(k, pts, box_lo, box_hi, first_leaf, n, false, raw, factor, out, d_clamped,
           result.neighbours_stored ? neighbours.data() : nullptr, progress, 0, weight);
    if (result.neighbours_stored)
        stored_clamp(pts, neighbours, n, k, raw, factor, out, d_clamped);
    else if (local)
        search(k, pts, box_lo, box_hi, first_leaf, n, true, raw, factor, out, d_clamped, nullptr, progress,
               n / 2, weight);
    neighbours.release();
    pts.release();
    box_lo.release();
    box_hi.release();
    result.seconds_search = now_seconds() - t;
    t = now_seconds();

    // The medians and the global clamp (radii.cpp clamp_radii).
    result.raw_median = median(raw, n);
    if (clamp == KnnClamp::global) {
        const float limit = static_cast<float>(double(factor) * result.raw_median);
        result.clamp_limit = limit;
        out.resize(n);
        launch_kernel(launch_1d(n, 256), global_clamp_kernel, raw.data(), n, limit, out.data(),
                      d_clamped.data());
    }
    const DeviceBuffer<float>& radii_out = clamp == KnnClamp::none ? raw : out;
    result.median = clamp == KnnClamp::none ? result.raw_median : median(radii_out, n);
    unsigned long long clamped = 0;
    d_clamped.download(&clamped, 1);
    radii_out.download(radii.data(), n);
    PRT_CUDA_CHECK(cudaDeviceSynchronize());
    result.clamped = clamped;
    result.seconds_clamp = now_seconds() - t;
    return result;
}

}  // namespace prt::cuda
