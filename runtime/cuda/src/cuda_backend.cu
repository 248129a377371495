// PointRT CUDA backend: kernels that call the shared core (prt/core/render.h), the same functions
// the CPU backend runs. Two kernel structures (thesis 2.4), chosen by measurement (prt-bench):
//   megakernel: one thread per pixel runs render_pixel(): generation, traversal, shading, shadow
//               and secondary rays in one kernel;
//   wavefront:  one kernel generates primary rays, then per bounce a trace kernel (closest hits)
//               and a shade kernel (shadow rays, local shading, secondary rays appended to the next
//               queue), then a post-process kernel (tone mapping), as in the thesis's Fig. 2.5.
// Rays map to threads in Z-order (thesis 2.3): a 256-thread block covers a 16x16 tile and each
// warp an 8x4 block of neighbouring pixels; a row-by-row mapping is kept for comparison.
// Never include PCL, OpenMesh or OpenImageIO here.
#include <cuda_runtime.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <utility>
#include <vector>

#include "cast_batch.h"
#include "cuda_brick_storage.h"
#include "cuda_check.h"
#include "device_buffer.h"
#include "prt/core/render.h"
#include "prt/cuda/cuda_backend.h"
#include "prt/cuda/device_scene.h"
#include "prt/runtime/walk_choice.h"

namespace prt::cuda {

namespace {

constexpr std::uint32_t k_block = 256;  // threads per block = one 16x16 tile
constexpr std::uint32_t k_tile = 16;

enum Counter : std::uint32_t {
    k_c_primary,
    k_c_secondary,
    k_c_shadow,
    k_c_leaves,
    k_c_splat_tests,
    k_c_truncated,
    k_c_sanitized,
    k_c_dropped,
    k_c_culled,
    k_c_fallbacks,
    k_counter_count
};

/// Sums each thread's counters over the block (warp reductions, then shared memory) and adds
/// them to the frame's 64-bit totals with one atomic per counter per block. Every thread of the
/// block must call it (no early returns before it).
__device__ void flush_counters(const core::RayCounters& c, unsigned long long* out) {
    __shared__ unsigned int block_sum[k_counter_count];
    if (threadIdx.x < k_counter_count) block_sum[threadIdx.x] = 0;
    __syncthreads();
    const unsigned int v[k_counter_count] = {c.primary,   c.secondary, c.shadow,  c.leaves, c.splat_tests,
                                             c.truncated, c.sanitized, c.dropped, c.culled, c.fallbacks};
    const bool lane0 = (threadIdx.x & 31u) == 0;
#pragma unroll
    for (std::uint32_t i = 0; i < k_counter_count; ++i) {
        const unsigned int s = __reduce_add_sync(0xffffffffu, v[i]);
        if (lane0 && s) atomicAdd(&block_sum[i], s);
    }
    __syncthreads();
    if (threadIdx.x < k_counter_count && block_sum[threadIdx.x]) {
        atomicAdd(&out[threadIdx.x], static_cast<unsigned long long>(block_sum[threadIdx.x]));
    }
}

__device__ __forceinline__ void store_pixel(const core::RenderParams& p, std::size_t i, core::Vec3 color,
                                            float* __restrict__ rgb, std::uint32_t* __restrict__ rgba) {
    rgb[i * 3 + 0] = color.x;
    rgb[i * 3 + 1] = color.y;
    rgb[i * 3 + 2] = color.z;
    rgba[i] = core::pack_rgba8(core::encode_display(color, p));
}

/// The pixel of lane `lane` of work item `item` (one warp's 32 pixels): in Z-order, item / 8 is a
/// 16x16 tile (row by row over `tiles_x` tiles) and item % 8 its 8x4 block; else pixels row by row.
template <bool k_zorder>
__device__ __forceinline__ void item_pixel(std::uint32_t item, std::uint32_t lane, std::uint32_t width,
                                           std::uint32_t tiles_x, std::uint32_t row_begin, std::uint32_t& x,
                                           std::uint32_t& y) {
    if constexpr (k_zorder) {
        constexpr std::uint32_t k_warps_per_tile = k_block / 32u;
        const std::uint32_t tile = item / k_warps_per_tile;
        std::uint32_t tx, ty;
        core::zorder_decode((item % k_warps_per_tile) * 32u + lane, tx, ty);
        x = (tile % tiles_x) * k_tile + tx;
        y = row_begin + (tile / tiles_x) * k_tile + ty;
    } else {
        const unsigned long long i = static_cast<unsigned long long>(item) * 32u + lane;
        x = static_cast<std::uint32_t>(i % width);
        y = row_begin + static_cast<std::uint32_t>(i / width);
    }
}

/// Heavy items first (the persistent megakernel's queue order). A frame's 32-pixel items differ in
/// cost by two orders of magnitude (H200, the teapot's primary frame at 1024^2: median 10.6k cycles,
/// the slowest 678k, at the gap between lid and body, where rays pass down many leaves), and an item
/// cannot be split: a heavy one taken late in the frame ends it alone (its SMs' finish spread from
/// 340 to 555 us). So every frame records each item's cycles and sorts the items that took more than
/// ItemOrder::factor times the frame's mean into k_heavy_classes lists by powers of two (over 16x
/// the factor, 8x, 4x, 2x, 1x); the next frame of the same shape (width and rows) hands out those
/// lists first, heaviest first, then the other items in image order: longest processing time first
/// (Graham 1969) with the previous frame as the estimate, since consecutive frames of one view, or
/// of a moving camera, cost nearly the same per item. The order changes no pixel. Measured on an
/// H200 (preprocess/bench/results/h200-2026-12-03-issue19-heavy-first), 1024^2 primary rays against
/// image order alone: teapot 1.79 -> 2.14 Grays/s, Bigguy 0.76 -> 0.83, prt-bench's room 1.03 -> 1.15,
/// the culled 10M-point sphere 1.21 -> 1.60 (ISO 1.49 -> 2.05); one list at factor 4 or 8 gained as
/// much on the teapot but nothing on the room, one at factor 2 the reverse; five classes at factor
/// 1.5 / 2 / 3: teapot 2.09 / 2.12 / 2.14, room 1.22 / 1.15 / 1.06.
inline constexpr std::uint32_t k_heavy_classes = 5;
struct OrderSlot {
    unsigned long long cycles;                  ///< the frame's item cycles, summed
    unsigned long long heavy[k_heavy_classes];  ///< items in each class's list, the heaviest first
};
struct ItemOrder {
    /// The previous frame's heavy items: k_heavy_classes lists of `items` entries, the heaviest first.
    const std::uint32_t* heavy = nullptr;
    std::uint32_t* next_heavy = nullptr;  ///< this frame's, for the next frame
    /// Per item: the last frame whose heavy lists hold it. An item stamped >= frame was handed out
    /// from a list (or was found heavy after its image-order turn), so its image-order turn skips it.
    std::uint32_t* stamp = nullptr;
    const OrderSlot* prev = nullptr;  ///< the previous frame's sums
    OrderSlot* next = nullptr;        ///< this frame's (zeroed before it starts)
    std::uint32_t frame = 0;          ///< this frame's number (0: no ordering, image order only)
    float factor = 2.0f;              ///< heavy: more cycles than factor x the mean item
};
static_assert(sizeof(OrderSlot) == (1 + k_heavy_classes) * sizeof(unsigned long long));
/// Words of the counter buffer before the counters: one OrderSlot (the other follows the queue).
constexpr std::size_t k_slot_words = sizeof(OrderSlot) / sizeof(unsigned long long);
constexpr std::size_t k_counters_at = k_slot_words;

/// The next item of the persistent queue (lane 0): the previous frame's heavy items, heaviest class
/// first, then every other item in image order; `items` when none are left.
__device__ std::uint32_t next_item(unsigned int* queue, const ItemOrder& order, std::uint32_t items) {
    for (;;) {  // bounded: every pass moves the queue on
        std::uint32_t q = atomicAdd(queue, 1u);
        if (order.frame == 0) return q < items ? q : items;
        for (std::uint32_t c = 0; c < k_heavy_classes; ++c) {
            const auto n = static_cast<std::uint32_t>(order.prev->heavy[c]);
            if (q < n) return order.heavy[static_cast<std::size_t>(c) * items + q];
            q -= n;
        }
        if (q >= items) return items;
        if (order.stamp[q] < order.frame) return q;
    }
}

/// After item `item` took `cycles` (lane 0): adds them to the frame's sum and lists the item for the
/// next frame when it took more than factor x `mean` cycles (the previous frame's mean item).
__device__ void record_item(const ItemOrder& order, std::uint32_t item, std::uint32_t items,
                            unsigned long long cycles, unsigned long long mean) {
    atomicAdd(&order.next->cycles, cycles);
    auto limit = static_cast<unsigned long long>(order.factor * static_cast<float>(mean));
    if (mean == 0 || cycles <= limit) return;
    std::uint32_t c = k_heavy_classes - 1;
    for (limit *= 2; c > 0 && cycles > limit; limit *= 2) --c;
    order.stamp[item] = order.frame + 1u;
    const auto slot = static_cast<std::uint32_t>(atomicAdd(&order.next->heavy[c], 1ull));
    order.next_heavy[static_cast<std::size_t>(c) * items + slot] = item;
}

/// Megakernel: one thread traces one pixel's whole ray tree (render_pixel). k_min_blocks is the
/// occupancy hint (resident 256-thread blocks per SM) that bounds the registers per thread; K the
/// code it carries (core::KernelMask): splats-only Whitted frames get a kernel without the other
/// surfaces and the path tracer (measured on an H200: the general kernel traced the 1M-point room's
/// primary rays at 0.84 Grays/s, the splat kernel at the H100's 1.13).
/// Persistent warps (Aila and Laine 2009, "Understanding the efficiency of ray traversal on GPUs",
/// 3): with `queue`, the grid holds only as many blocks as fit on the GPU at once and each warp
/// takes its next 32 pixels (`items` in all) from the queue until none are left, so a block whose
/// warps finish early does not wait on its slowest warp before the SM gets new work; without it,
/// one 32-pixel item per warp from the block index. `order`: the queue's heavy items first (ItemOrder).
template <bool k_zorder, int k_min_blocks, std::uint32_t K = core::k_mask_splats>
__global__ void __launch_bounds__(k_block, k_min_blocks)
    render_kernel(const core::SceneView scene, const core::PinholeCamera cam, std::uint32_t width,
                  std::uint32_t height, std::uint32_t row_begin, std::uint32_t row_end,
                  float* __restrict__ rgb, std::uint32_t* __restrict__ rgba, unsigned long long* counters,
                  unsigned int* queue, std::uint32_t items, std::uint32_t tiles_x, const ItemOrder order) {
    const std::uint32_t lane = threadIdx.x & 31u;
    core::RayCounters c;
    std::uint32_t item = (blockIdx.y * gridDim.x + blockIdx.x) * (k_block / 32u) + threadIdx.x / 32u;
    const bool ordered = queue != nullptr && order.frame != 0;
    const unsigned long long mean = ordered ? order.prev->cycles / items : 0;  // 0: nothing is heavy yet
    for (;;) {  // bounded: every pass takes a new item from the queue, or ends
        if (queue != nullptr) {
            std::uint32_t next = 0;
            if (lane == 0) next = next_item(queue, order, items);
            item = __shfl_sync(0xffffffffu, next, 0);
        }
        if (item >= items) break;
        const long long t0 = clock64();
        std::uint32_t x, y;
        item_pixel<k_zorder>(item, lane, width, tiles_x, row_begin, x, y);
        if (x < width && y < row_end) {
            const core::Vec3 color = core::render_pixel<K>(scene, cam, x, y, width, height, c);
            store_pixel(scene.params, static_cast<std::size_t>(y) * width + x, color, rgb, rgba);
        }
        if (queue == nullptr) break;
        if (ordered) {
            __syncwarp();
            if (lane == 0)
                record_item(order, item, items, static_cast<unsigned long long>(clock64() - t0), mean);
        }
    }
    flush_counters(c, counters);
}

// ---- The megakernels this build has ----------------------------------------------------------------

using RenderKernel = void (*)(core::SceneView, core::PinholeCamera, std::uint32_t, std::uint32_t,
                              std::uint32_t, std::uint32_t, float*, std::uint32_t*, unsigned long long*,
                              unsigned int*, std::uint32_t, std::uint32_t, ItemOrder);

/// One megakernel variant: the code it carries (core::KernelMask: splats only, patches only, or
/// everything with sampling), its occupancy hint (--min-blocks) and its two ray mappings.
struct Megakernel {
    std::uint32_t mask;
    int min_blocks;
    RenderKernel zorder, linear;
};

template <std::uint32_t K, int k_min_blocks>
Megakernel megakernel() {
    return {K, k_min_blocks, render_kernel<true, k_min_blocks, K>, render_kernel<false, k_min_blocks, K>};
}

constexpr std::uint32_t k_secondary = core::k_mask_secondary;
constexpr std::uint32_t k_plain = core::k_mask_plain_walk;

/// The megakernels compiled in: by default the ones the defaults (--min-blocks 0) and the GPU tests
/// launch (kernel_mask() chooses). Splats, bricked splats and patches have their own kernels for
/// frames with that surface kind alone (without the other surfaces' registers), each twice: with
/// reflected and refracted rays (k_secondary) and without, for frames that spawn none
/// (core::spawns_secondary: no bounces, or no reflective or transmissive material). ISO has its own
/// three at 3 blocks per SM (the third for frames with shadow rays and no secondary ray,
/// core::k_mask_shadow_walk); MLS has its own at 2 blocks per SM, with and without secondary rays;
/// everything else (mixed surfaces, spp > 1, path tracing) runs the general kernel. sm_90 local memory (stack
/// frame, spill stores): splats 328 / 440 B without secondary rays against 1648 / 708 B with them, ISO (3
/// blocks per SM) 248 / 156 B against the general kernel's 4960 / 7542 B. On an H200 (1024^2, Grays/s,
/// preprocess/bench/results/h200-2026-12-02-issue19-kernels), primary / shadow: prt-bench's room
/// 1.00 / 1.56 -> 1.16 / 1.78, the culled 10M sphere 1.15 / 1.31 -> 1.37 / 1.49, bricked splats
/// (culled room) 1.18 / 1.10 -> 1.32 / 1.14, ISO (culled room) 1.02 / 1.06 -> 1.57 / 1.36, teapot
/// 1.24 / 0.75 -> 1.42 / 0.82. An ISO kernel with secondary rays was slower than the general one on
/// full4 (0.535 against 0.731; its closest-hit and shadow walks took turns within a warp) until its
/// rays shared one walk loop (core::trace_ray_shared): then H100, 2026-12-06, the general kernel ->
/// this one, reflect4 / full4 Grays/s: the culled room's ISO from outside 0.99 / 0.70 -> 1.34 / 1.34,
/// from bench_room.json's camera 1.05 / 1.07 -> 1.47 / 2.07, the culled 10M sphere's full4 0.95 ->
/// 1.75 (4 blocks per SM: 1.34-1.35 / 1.37, 1.42 / 2.01-2.02, 1.56;
/// preprocess/bench/results/h100-2026-12-06-issue19-iso-shared). MLS kernels at 4 blocks per SM were slower
/// than the general kernel (primary 0.034 against 0.037), but at 2 (128 registers: the four sample
/// lanes' sums, no spills) much faster: the culled room's primary / shadow 0.036 / 0.033 -> 0.097 /
/// 0.078 Grays/s (1 block: 0.077 / 0.060, 3: 0.064 / 0.051, 4: 0.034 / 0.030), and 0.129 / 0.096 with
/// the while-while walk of core/mls.h (H200, preprocess/bench/results/h200-2026-12-03-issue19-mls).
/// Occupancy: the general kernel at 4 blocks per SM, patches at 2, ISO at 3 (H200, the
/// culled 1M room, primary / shadow at 2, 3, 4, 5 blocks: 1.43 / 1.21, 1.57 / 1.36, 1.36 / 1.39,
/// 1.11 / 1.25 Grays/s), splats at 3: 4 was the best on 2026-12-02 (without secondary rays, prt-bench's
/// room at 2 / 3 / 4 / 5: 0.88 / 1.37, 1.09 / 1.66, 1.16 / 1.78, 1.05 / 1.66; gpu-k4.sh there), but
/// it spilled there (above) and its walk has grown since (macro-regions): H100, 2026-12-06, 4 -> 3
/// blocks, primary / shadow / reflect4 / full4 Grays/s: the culled room (bench_room.json) 2.14 / 2.97 /
/// 1.25 / 1.54 -> 2.71-2.73 / 3.29-3.36 / 1.57 / 1.68, prt-bench's room 1.37 / 2.07-2.10 / 0.615 / 0.99
/// -> 1.48 / 2.17 / 0.71 / 1.11, the culled 10M sphere 1.52-1.53 / 1.46 / 1.48-1.49 / 1.33 -> 1.71 /
/// 1.54 / 1.75-1.76 / 1.44, the culled 1M sphere 2.20 / 2.14-2.15 / 2.01-2.02 -> 2.66-2.67 / 2.28 /
/// 2.50 (2 blocks: reflect4 / full4 1.43 / 1.55 on the room, 5: primary 1.30;
/// preprocess/bench/results/h100-2026-12-06-issue19-occupancy), bricked
/// splats (issue 17: their own kernel, so the float splat kernel does not carry the brick walk) at 3
/// (H100, culled 1M sphere, Grays/s primary / shadow / reflect4: 1.297 / 1.774 / 1.757 at 3, 1.177 /
/// 1.658 / 1.479 at 4, 1.193 / 1.619 / 1.605 at 2; preprocess/bench/results/h100-2026-11-25-issue17-onewalk).
/// The bricked kernel carries the brick walk alone, not the float splat code too (a scene mixing float
/// and bricked splat models takes the general kernel): 740 B of spills at 3 blocks against 824, and
/// on an H200 shadow rays 5-7 % faster, full4 5-6 %, primary under 1 %; 4 blocks were 6-8 % slower on
/// primary rays there (preprocess/bench/results/h200-2026-11-28-issue17-direct). The tuning variants of
/// --min-blocks (with secondary rays: splats 1, 2, 4, 5, 6; patches 1, 4; bricked splats 2, 4; ISO 2,
/// 4; without: splats 2, 4, 5, bricked splats 2, 4, ISO 2, 4, 5, plain ISO 2, 4: runtime/README.md) only with
/// the CMake option PRT_CUDA_TUNING_KERNELS, so a default build compiles 15 megakernels instead of 39. ISO's
/// three come twice: also compiled without macro-region code (k_plain, WalkChoice).
const Megakernel k_megakernels[] = {
    // clang-format off
    megakernel<core::k_mask_splats, 3>(),  megakernel<core::k_mask_splats | k_secondary, 3>(),
    megakernel<core::k_mask_bricks, 3>(),  megakernel<core::k_mask_bricks | k_secondary, 3>(),
    megakernel<core::k_mask_patches, 2>(), megakernel<core::k_mask_patches | k_secondary, 2>(),
    megakernel<core::k_mask_iso, 3>(),     megakernel<core::k_mask_iso | k_secondary, 3>(),
    megakernel<core::k_mask_iso | core::k_mask_shadow_walk, 3>(),
    megakernel<core::k_mask_iso | k_plain, 3>(),  megakernel<core::k_mask_iso | k_secondary | k_plain, 3>(),
    megakernel<core::k_mask_iso | core::k_mask_shadow_walk | k_plain, 3>(),
    megakernel<core::k_mask_mls, 2>(),     megakernel<core::k_mask_mls | k_secondary, 2>(),
    megakernel<core::k_mask_all, 4>(),     // every surface, sampling, secondary rays
#if PRT_CUDA_TUNING_KERNELS
    megakernel<core::k_mask_splats | k_secondary, 1>(),
    megakernel<core::k_mask_splats | k_secondary, 2>(),
    megakernel<core::k_mask_splats | k_secondary, 4>(),
    megakernel<core::k_mask_splats | k_secondary, 5>(),
    megakernel<core::k_mask_splats | k_secondary, 6>(),
    megakernel<core::k_mask_patches | k_secondary, 1>(),
    megakernel<core::k_mask_patches | k_secondary, 4>(),
    megakernel<core::k_mask_bricks | k_secondary, 2>(),
    megakernel<core::k_mask_bricks | k_secondary, 4>(),
    megakernel<core::k_mask_splats, 2>(),
    megakernel<core::k_mask_splats, 4>(),
    megakernel<core::k_mask_splats, 5>(),
    megakernel<core::k_mask_bricks, 2>(),
    megakernel<core::k_mask_bricks, 4>(),
    megakernel<core::k_mask_iso, 2>(),
    megakernel<core::k_mask_iso, 4>(),
    megakernel<core::k_mask_iso, 5>(),
    megakernel<core::k_mask_iso | k_secondary, 2>(),
    megakernel<core::k_mask_iso | k_secondary, 4>(),
    megakernel<core::k_mask_iso | k_plain, 2>(),
    megakernel<core::k_mask_iso | k_plain, 4>(),
    megakernel<core::k_mask_mls, 1>(),
    megakernel<core::k_mask_mls, 3>(),
    megakernel<core::k_mask_mls, 4>(),
#endif
    // clang-format on
};

/// The code a frame's kernel carries (k_megakernels): `surface_mask` is core::scene_mask() without
/// k_mask_sampling; `sampling`: spp > 1 or path tracing; `secondary`: core::spawns_secondary();
/// `shadows`: the frame traces shadow rays (ISO frames without secondary rays then take the kernel
/// whose closest hits and shadow rays share one walk loop, core::k_mask_shadow_walk); `plain`: ISO
/// kernels walk without macro-region code (core::k_mask_plain_walk).
std::uint32_t kernel_mask(std::uint32_t surface_mask, bool sampling, bool secondary, bool shadows,
                          bool plain) {
    if (sampling) return core::k_mask_all;
    switch (surface_mask) {
        case core::k_mask_iso:
            if (plain) return kernel_mask(surface_mask, false, secondary, shadows, false) | k_plain;
            if (!secondary && shadows) return surface_mask | core::k_mask_shadow_walk;
            [[fallthrough]];
        case core::k_mask_splats:
        case core::k_mask_bricks:
        case core::k_mask_patches:
        case core::k_mask_mls:
            return secondary ? surface_mask | k_secondary : surface_mask;
        default:
            return core::k_mask_all;  // mixed surfaces
    }
}

/// The megakernel a frame needs (kernel_mask()) at its occupancy: --min-blocks `asked` (1-6;
/// anything else: the kernel's default). Patch-only kernels: 2 by default (128 registers), 1 (all it
/// needs, ~255) or 4 for 3-6 (64: heavy spilling). Measured on an H100 (issue #8), teapot primary /
/// shadow / one reflection: 1.26 / 0.83 / 0.83 Grays/s at 2, 1.27 / 0.82 / 0.76 at 1, 0.76 / 0.53 /
/// 0.49 at 4; Bigguy 0.76 / 0.54 / 0.27 at 2, 0.86 / 0.61 / 0.26 at 1. The general kernel exists
/// at its default occupancy only; a tuning variant with secondary rays serves frames without them
/// where the build has none without; a plain ISO walk (`plain`) at an occupancy it is not compiled
/// for gives the walk with regions. Throws prt::Error (one line) when this build lacks the variant.
const Megakernel& find_megakernel(std::uint32_t surface_mask, bool sampling, bool secondary, bool shadows,
                                  int asked, bool plain = false) {
    const std::uint32_t mask = kernel_mask(surface_mask, sampling, secondary, shadows, plain);
    const std::uint32_t kind = mask & ~(k_secondary | core::k_mask_shadow_walk | k_plain);
    if (asked < 1 || asked > 6) asked = 0;
    int blocks = 4;  // the general kernel's only occupancy
    if (kind == core::k_mask_patches)
        blocks = asked == 0 ? 2 : (asked <= 2 ? asked : 4);  // variants 1, 2 and 4
    else if (kind == core::k_mask_bricks)
        blocks = asked == 0 ? 3 : asked;  // variants 2, 3 and 4
    else if (kind == core::k_mask_iso)
        blocks = asked == 0 ? 3 : asked;  // variants 2, 3, 4 and 5
    else if (kind == core::k_mask_splats)
        blocks = asked == 0 ? 3 : asked;  // variants 1-6 with secondary rays, 2-5 without
    else if (kind == core::k_mask_mls)
        blocks = asked == 0 ? 2 : asked;  // variants 1, 2, 3 and 4
    for (const std::uint32_t walk : {mask, mask & ~k_plain}) {
        const std::uint32_t no_shadow_walk = walk & ~std::uint32_t{core::k_mask_shadow_walk};
        for (const std::uint32_t m : {walk, no_shadow_walk, no_shadow_walk | k_secondary})
            for (const Megakernel& k : k_megakernels)
                if (k.mask == m && k.min_blocks == blocks) return k;
    }
    throw Error(
        std::string("CUDA: --min-blocks ") + std::to_string(asked) + " selects the " +
        (kind == core::k_mask_patches ? "patch"
         : kind == core::k_mask_iso   ? "ISO"
         : kind == core::k_mask_mls   ? "MLS"
                                      : "splat") +
        " kernel for " + std::to_string(blocks) +
        " blocks per SM, a tuning variant this build lacks (configure with -DPRT_CUDA_TUNING_KERNELS=ON)");
}

// ---- Wavefront kernels (thesis 2.4, Fig. 2.5) ---------------------------------------------------

constexpr std::uint32_t k_no_pixel = 0xffffffffu;

struct WaveRay {
    core::PendingRay ray;
    std::uint32_t pixel;  ///< k_no_pixel for padding slots
};

struct WaveHit {
    core::SurfaceHit hit;
    std::uint32_t valid;
};

template <bool k_zorder>
__global__ void __launch_bounds__(k_block)
    wave_primary(const core::PinholeCamera cam, std::uint32_t width, std::uint32_t height,
                 std::uint32_t row_begin, std::uint32_t row_end, WaveRay* __restrict__ queue,
                 float* __restrict__ accum, unsigned long long* counters) {
    // One 32-pixel item per warp from the block index: the grid is one block per 16x16 tile
    // (Z-order) or per 256 pixels (linear).
    std::uint32_t x, y;
    item_pixel<k_zorder>((blockIdx.y * gridDim.x + blockIdx.x) * (k_block / 32u) + threadIdx.x / 32u,
                         threadIdx.x & 31u, width, gridDim.x, row_begin, x, y);
    const std::uint32_t slot = (blockIdx.y * gridDim.x + blockIdx.x) * k_block + threadIdx.x;
    WaveRay r;
    r.pixel = k_no_pixel;
    core::RayCounters c;
    if (x < width && y < row_end) {
        ++c.primary;
        r.pixel = y * width + x;
        r.ray = core::PendingRay{core::primary_ray(cam, x, y, width, height), core::Vec3{1, 1, 1}, 0};
        accum[r.pixel * 3 + 0] = 0.0f;
        accum[r.pixel * 3 + 1] = 0.0f;
        accum[r.pixel * 3 + 2] = 0.0f;
    }
    queue[slot] = r;
    flush_counters(c, counters);
}

__global__ void __launch_bounds__(k_block)
    wave_trace(const core::SceneView scene, const WaveRay* __restrict__ queue,
               const std::uint32_t* __restrict__ count, std::uint32_t fixed_count, WaveHit* __restrict__ hits,
               unsigned long long* counters) {
    const std::uint32_t i = blockIdx.x * k_block + threadIdx.x;
    const std::uint32_t n = count ? *count : fixed_count;
    core::RayCounters c;
    if (i < n && queue[i].pixel != k_no_pixel) {
        WaveHit h;
        h.valid = core::closest_hit_scene(scene, queue[i].ray.ray, h.hit, c) ? 1u : 0u;
        hits[i] = h;
    }
    flush_counters(c, counters);
}

__global__ void __launch_bounds__(k_block)
    wave_shade(const core::SceneView scene, const WaveRay* __restrict__ queue,
               const std::uint32_t* __restrict__ count, std::uint32_t fixed_count,
               const WaveHit* __restrict__ hits, WaveRay* __restrict__ next,
               std::uint32_t* __restrict__ next_count, std::uint32_t capacity, float* __restrict__ accum,
               unsigned long long* counters) {
    const std::uint32_t i = blockIdx.x * k_block + threadIdx.x;
    const std::uint32_t n = count ? *count : fixed_count;
    core::RayCounters c;
    if (i < n && queue[i].pixel != k_no_pixel) {
        const WaveRay r = queue[i];
        const WaveHit h = hits[i];
        core::Vec3 add;
        if (!h.valid) {
            add = r.ray.weight * core::background(scene.environment, r.ray.ray.dir);
        } else {
            add = r.ray.weight * core::shade_hit(scene, r.ray.ray, h.hit, c);
            core::PendingRay spawned[2];
            const std::uint32_t k = core::spawn_secondary(scene, r.ray, h.hit, spawned);
            c.secondary += k;
            if (k > 0) {
                const std::uint32_t at = atomicAdd(next_count, k);
                for (std::uint32_t j = 0; j < k; ++j) {
                    if (at + j < capacity)
                        next[at + j] = WaveRay{spawned[j], r.pixel};
                    else
                        ++c.dropped;
                }
            }
        }
        atomicAdd(&accum[r.pixel * 3 + 0], add.x);
        atomicAdd(&accum[r.pixel * 3 + 1], add.y);
        atomicAdd(&accum[r.pixel * 3 + 2], add.z);
    }
    flush_counters(c, counters);
}

__global__ void __launch_bounds__(k_block)
    wave_finish(const core::RenderParams params, std::uint32_t width, std::uint32_t row_begin,
                std::uint32_t row_end, const float* __restrict__ accum, float* __restrict__ rgb,
                std::uint32_t* __restrict__ rgba, unsigned long long* counters) {
    const unsigned long long i = static_cast<unsigned long long>(blockIdx.x) * k_block + threadIdx.x +
                                 static_cast<unsigned long long>(row_begin) * width;
    core::RayCounters c;
    if (i < static_cast<unsigned long long>(row_end) * width) {
        core::Vec3 color{accum[i * 3], accum[i * 3 + 1], accum[i * 3 + 2]};
        if (!core::is_finite(color)) {
            color = core::Vec3{0, 0, 0};
            ++c.sanitized;
        }
        store_pixel(params, i, color, rgb, rgba);
    }
    flush_counters(c, counters);
}

// ---- Host side --------------------------------------------------------------------------------

class CudaBackend final : public rt::Backend {
public:
    explicit CudaBackend(const rt::BackendOptions& options) : m_options(options) {
        std::string why;
        if (!device_available(&why)) throw Error(why);
        PRT_CUDA_CHECK(cudaSetDevice(0));
        cudaDeviceProp prop{};
        PRT_CUDA_CHECK(cudaGetDeviceProperties(&prop, 0));
        m_device = std::string(prop.name) + " (" + std::to_string(prop.multiProcessorCount) + " SMs, sm_" +
                   std::to_string(prop.major) + std::to_string(prop.minor) + ")";
        PRT_CUDA_CHECK(cudaStreamCreateWithFlags(&m_stream, cudaStreamNonBlocking));
        PRT_CUDA_CHECK(cudaEventCreate(&m_start));
        PRT_CUDA_CHECK(cudaEventCreate(&m_stop));
        // [order slot 0, the counters, the persistent megakernel's work queue, order slot 1]
        m_counters.resize(k_counters_at + k_counter_count + 1 + k_slot_words);
        m_sm_count = static_cast<std::uint32_t>(prop.multiProcessorCount);
        const std::string& walk = m_options.cuda_iso_walk;
        if (walk != "auto" && walk != "regions" && walk != "plain")
            throw Error("CUDA: unknown ISO walk \"" + walk + "\" (expected auto, regions or plain)");
    }
    ~CudaBackend() override {
        if (m_stream) cudaStreamSynchronize(m_stream);
        if (m_start) cudaEventDestroy(m_start);
        if (m_stop) cudaEventDestroy(m_stop);
        if (m_stream) cudaStreamDestroy(m_stream);
    }

    std::string name() const override { return "cuda"; }
    std::string device() const override { return m_device; }

    // Streamed bricks (issue 17, rt::BrickStream): a device arena and tables per bricked model.
    std::unique_ptr<rt::BrickStorage> make_brick_storage(std::uint32_t model, const core::BrickView&,
                                                         const rt::BrickArena& arena) override {
        return make_cuda_brick_storage(m_device_scene, model, arena);
    }
    std::uint64_t default_memory_budget() const override { return cuda::default_memory_budget(); }

    rt::UploadStats set_scene(const core::SceneView& host) override {
        const std::uint32_t mask = core::scene_mask(host) & ~std::uint32_t{core::k_mask_sampling};
        find_megakernel(mask, false, true, false,
                        m_options.cuda_min_blocks);  // a variant this build lacks: fail now
        const rt::UploadStats stats = m_device_scene.upload(host, m_stream);
        m_surface_mask = mask;
        m_secondary_materials = core::secondary_materials(host.materials, host.material_count);
        m_shadow_lights = core::casts_any_shadow(host.lights, host.light_count);
        m_iso_regions = false;
        for (std::uint32_t i = 0; i < host.model_count; ++i)
            m_iso_regions = m_iso_regions || (host.models[i].surface == core::SurfaceKind::iso &&
                                              host.models[i].iso.tree.macro_regions != nullptr);
        m_walk_choice = rt::WalkChoice{};
        m_scene = m_device_scene.view();
        warm_megakernels();
        return stats;
    }

    rt::FrameStats render(const rt::FrameRequest& req, rt::Image& image) override {
        const auto start = std::chrono::steady_clock::now();
        const std::uint32_t w = req.width, h = req.height;
        const std::uint32_t y0 = std::min(req.row_begin, h);
        const std::uint32_t y1 = req.row_end == 0 ? h : std::min(req.row_end, h);
        rt::FrameStats stats;
        stats.pixels = static_cast<std::uint64_t>(w) * (y1 - y0);
        if (image.width != w || image.height != h) image.resize(w, h);
        if (stats.pixels == 0) return stats;
        const std::size_t pixels = static_cast<std::size_t>(w) * h;
        m_rgb.reserve(pixels * 3);
        m_rgba.reserve(pixels);
        core::SceneView scene = m_scene;
        scene.params = req.params;
        core::set_lod_cone(scene.params, req.camera, req.height);
        // Sampled frames (spp > 1, path tracing: seed 002, 7) run in the megakernel only.
        const bool wavefront =
            m_options.cuda_wavefront && scene.params.spp <= 1 && scene.params.path_tracing == 0;
        const std::uint32_t order_frame =
            zero_counters(w, y0, y1, m_options.cuda_heavy_first && m_options.cuda_persistent && !wavefront);
        PRT_CUDA_CHECK(cudaEventRecord(m_start, m_stream));
        bool timed_walk = false;  // WalkChoice waits for this frame's time
        if (wavefront) {
            render_wavefront(scene, req, w, h, y0, y1);
        } else {
            timed_walk = render_megakernel(scene, req, w, h, y0, y1, order_frame);
        }
        PRT_CUDA_CHECK(cudaEventRecord(m_stop, m_stream));
        unsigned long long counters[k_counter_count];
        m_counters.download(counters, k_counter_count, k_counters_at, m_stream);
        OrderSlot used{};  // the sums this frame's order came from
        if (order_frame != 0) {
            const std::size_t at =
                reinterpret_cast<unsigned long long*>(order_slot(order_frame)) - m_counters.data();
            m_counters.download(reinterpret_cast<unsigned long long*>(&used), k_slot_words, at, m_stream);
        }
        if (req.download) {
            const std::size_t first = static_cast<std::size_t>(y0) * w,
                              count = static_cast<std::size_t>(y1 - y0) * w;
            m_rgb.download(image.rgb.data() + first * 3, count * 3, first * 3, m_stream);
            if (!req.device_rgba8) m_rgba.download(image.rgba8.data() + first, count, first, m_stream);
        }
        PRT_CUDA_CHECK(cudaStreamSynchronize(m_stream));
        float ms = 0;
        PRT_CUDA_CHECK(cudaEventElapsedTime(&ms, m_start, m_stop));
        stats.device_ms = ms;
        if (timed_walk) m_walk_choice.record(ms * 1e6f / static_cast<float>(stats.pixels));  // ns per pixel
        stats.primary = counters[k_c_primary];
        stats.secondary = counters[k_c_secondary];
        stats.shadow = counters[k_c_shadow];
        stats.leaves = counters[k_c_leaves];
        stats.splat_tests = counters[k_c_splat_tests];
        stats.truncated = counters[k_c_truncated];
        stats.sanitized = counters[k_c_sanitized];
        stats.dropped = counters[k_c_dropped];
        stats.culled = counters[k_c_culled];
        stats.fallbacks = counters[k_c_fallbacks];
        for (const unsigned long long n : used.heavy) stats.heavy_first += n;
        stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return stats;
    }

    // Ray batches (issue 18): cast.cu's kernels on this device scene and stream.
    rt::CastStats cast(const core::CastRays& rays, const core::CastOutputs& out, rt::Memory memory) override {
        return cast_batch(cast_context(), rays, out, memory);
    }
    rt::CastStats occluded(const core::CastRays& rays, std::uint8_t* flags, std::uint8_t* valid,
                           rt::Memory memory) override {
        return occluded_batch(cast_context(), rays, flags, valid, memory);
    }

private:
    CastContext cast_context() {
        return CastContext{m_scene, m_surface_mask, m_stream, m_start, m_stop, &m_staging};
    }

    /// Where the kernels write the display-encoded frame: the caller's device buffer (a mapped GL
    /// pixel buffer in the window) or the backend's own.
    std::uint32_t* rgba_target(const rt::FrameRequest& req) {
        return req.device_rgba8 ? static_cast<std::uint32_t*>(req.device_rgba8) : m_rgba.data();
    }

    /// A megakernel's resident blocks per SM, asked once per kernel; the first call also sets its
    /// L1 preference: traversal reads through L1, so the largest L1 share (the kernel needs 32 B of
    /// shared memory) unless BackendOptions::cuda_max_l1 is off.
    std::uint32_t resident_blocks(RenderKernel kernel) {
        for (const auto& [k, n] : m_resident_blocks)
            if (k == kernel) return n;
        PRT_CUDA_CHECK(cudaFuncSetAttribute(kernel, cudaFuncAttributePreferredSharedMemoryCarveout,
                                            m_options.cuda_max_l1 ? int(cudaSharedmemCarveoutMaxL1) : -1));
        int per_sm = 0;
        PRT_CUDA_CHECK(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_sm, kernel, k_block, 0));
        m_resident_blocks.emplace_back(kernel, static_cast<std::uint32_t>(std::max(1, per_sm)));
        return m_resident_blocks.back().second;
    }

    /// The megakernel's 32-pixel work items for rows [y0, y1): 8 per 16x16 tile (Z-order) or 32
    /// pixels row by row.
    std::uint32_t item_count(std::uint32_t w, std::uint32_t y0, std::uint32_t y1) const {
        if (m_options.cuda_linear_mapping)
            return static_cast<std::uint32_t>((static_cast<unsigned long long>(w) * (y1 - y0) + 31u) / 32u);
        return (w + k_tile - 1) / k_tile * ((y1 - y0 + k_tile - 1) / k_tile) * (k_block / 32u);
    }

    /// Zeroes the frame's counters and work queue before it starts, and with `ordered` moves the
    /// item order (ItemOrder) to this frame: the same shape as the last ordered frame continues
    /// from its heavy list and sums (its slot kept, the other zeroed with the counters, one memset);
    /// a new shape starts without (both slots zeroed, and the frame number moved past every stamp).
    /// Returns the frame's order number (0: not ordered).
    std::uint32_t zero_counters(std::uint32_t w, std::uint32_t y0, std::uint32_t y1, bool ordered) {
        if (!ordered) {
            PRT_CUDA_CHECK(cudaMemsetAsync(m_counters.data() + k_counters_at, 0,
                                           (k_counter_count + 1) * sizeof(unsigned long long), m_stream));
            return 0;
        }
        const std::uint32_t items = item_count(w, y0, y1);
        const std::array<std::uint32_t, 4> shape{w, y0, y1, items};
        if (shape != m_order_shape || m_order_frame == 0) {
            m_order_shape = shape;
            for (auto& list : m_order_heavy) list.reserve(std::size_t{k_heavy_classes} * items);
            if (m_order_stamp.size() < items) {
                m_order_stamp.resize(items);
                PRT_CUDA_CHECK(cudaMemsetAsync(m_order_stamp.data(), 0, m_order_stamp.bytes(), m_stream));
            }
            m_order_frame += 2;  // past every stamp (<= the last frame + 1)
            PRT_CUDA_CHECK(cudaMemsetAsync(m_counters.data(), 0, m_counters.bytes(), m_stream));
        } else {
            m_order_frame += 1;
            // the next slot and the counters lie side by side: slot 0 before them, slot 1 after
            const std::size_t first = (m_order_frame + 1) % 2 == 0 ? 0 : k_counters_at;
            PRT_CUDA_CHECK(cudaMemsetAsync(m_counters.data() + first, 0,
                                           (k_slot_words + k_counter_count + 1) * sizeof(unsigned long long),
                                           m_stream));
        }
        return m_order_frame;
    }

    /// The persistent megakernel's work-queue counter: the word after the frame counters (zeroed
    /// with them before every frame).
    unsigned int* queue_counter() {
        return reinterpret_cast<unsigned int*>(m_counters.data() + k_counters_at + k_counter_count);
    }

    /// The order slot (OrderSlot) of frame `frame`'s sums.
    OrderSlot* order_slot(std::uint32_t frame) {
        return reinterpret_cast<OrderSlot*>(m_counters.data() +
                                            (frame % 2 == 0 ? 0 : k_counters_at + k_counter_count + 1));
    }

    /// Launches the scene's Whitted megakernels (with and without secondary rays) once with no
    /// items, so that the first frame does not pay for their first launch: CUDA loads a kernel's
    /// code when it first runs (lazy module loading, the default since CUDA 12.2) and sizes the
    /// local memory its stack frame needs then. Measured on an H200 (the 500M room under an eighth
    /// of its pool, preprocess/bench/results/h200-2026-12-04-issue19-timed-order, u2.txt): the
    /// orbit's first pass rendered in 14 ms with this, 44-72 ms without (the next pass: 3-4 ms).
    void warm_megakernels() {
        if (m_options.cuda_wavefront) return;
        // no secondary ray, with shadow rays, secondary rays; then the same walking ISO without regions
        for (const int variant : {0, 1, 2, 3, 4, 5}) {
            if (variant >= 3 && m_surface_mask != core::k_mask_iso) break;
            const Megakernel& k = find_megakernel(m_surface_mask, false, variant % 3 == 2, variant % 3 == 1,
                                                  m_options.cuda_min_blocks, variant >= 3);
            const RenderKernel kernel = m_options.cuda_linear_mapping ? k.linear : k.zorder;
            const std::uint32_t blocks = m_options.cuda_persistent ? resident_blocks(kernel) * m_sm_count : 1;
            launch_kernel(launch_grid(dim3(blocks), k_block, m_stream), kernel, m_scene,
                          core::PinholeCamera{}, 1u, 1u, 0u, 0u, m_rgb.data(), m_rgba.data(),
                          m_counters.data() + k_counters_at,
                          m_options.cuda_persistent ? queue_counter() : nullptr, 0u, 1u, ItemOrder{});
        }
        PRT_CUDA_CHECK(cudaStreamSynchronize(m_stream));
    }

    /// Whether a frame of kernel mask `mask` (regions walked) and size w x h walks an ISO without
    /// macro-region code (BackendOptions::cuda_iso_walk): always when no ISO model has regions (the
    /// same leaves, less code); else "regions", "plain", or for "auto" WalkChoice's answer, `timed`
    /// then set (the frame's time goes to WalkChoice::record). Only ISO-only kernels have the choice.
    bool plain_iso_walk(std::uint32_t mask, std::uint32_t w, std::uint32_t h, bool& timed) {
        timed = false;
        if ((mask & ~(k_secondary | core::k_mask_shadow_walk)) != core::k_mask_iso) return false;
        if (!m_iso_regions || m_options.cuda_iso_walk == "plain") return true;
        if (m_options.cuda_iso_walk == "regions") return false;
        timed = true;
        return m_walk_choice.next({mask, w, h}) == 1;
    }

    /// The megakernel over rows [y0, y1); `order_frame`: zero_counters()'s frame number. Returns
    /// whether the frame's time goes to m_walk_choice (plain_iso_walk).
    bool render_megakernel(const core::SceneView& scene, const rt::FrameRequest& req, std::uint32_t w,
                           std::uint32_t h, std::uint32_t y0, std::uint32_t y1, std::uint32_t order_frame) {
        const bool z = !m_options.cuda_linear_mapping;
        const std::uint32_t tiles_x = (w + k_tile - 1) / k_tile;
        const std::uint32_t items = item_count(w, y0, y1);
        const std::uint32_t item_blocks = (items + k_block / 32u - 1) / (k_block / 32u);
        auto launch = [&](RenderKernel kernel) {
            unsigned int* queue = nullptr;
            std::uint32_t blocks = item_blocks;
            ItemOrder order;
            if (m_options.cuda_persistent) {
                // As many blocks as the GPU holds at once; the queue counter sits after the counters
                // (zeroed with them every frame).
                blocks = std::min<std::uint32_t>(item_blocks, resident_blocks(kernel) * m_sm_count);
                queue = queue_counter();
                if (order_frame != 0) {
                    const std::uint32_t f = order_frame;
                    order.heavy = m_order_heavy[f % 2].data();
                    order.next_heavy = m_order_heavy[(f + 1) % 2].data();
                    order.stamp = m_order_stamp.data();
                    order.prev = order_slot(f);
                    order.next = order_slot(f + 1);
                    order.frame = f;
                }
            } else {
                resident_blocks(kernel);  // sets the kernel's L1 preference
            }
            launch_kernel(launch_grid(dim3(blocks), k_block, m_stream), kernel, scene, req.camera, w, h, y0,
                          y1, m_rgb.data(), rgba_target(req), m_counters.data() + k_counters_at, queue, items,
                          tiles_x, order);
        };
        const bool sampling = scene.params.spp > 1 || scene.params.path_tracing != 0;
        const bool secondary = core::spawns_secondary(scene.params, m_secondary_materials);
        const bool shadows = scene.params.shadows != 0 && m_shadow_lights;
        bool timed = false;
        const bool plain =
            plain_iso_walk(kernel_mask(m_surface_mask, sampling, secondary, shadows, false), w, h, timed);
        const Megakernel& k =
            find_megakernel(m_surface_mask, sampling, secondary, shadows, m_options.cuda_min_blocks, plain);
        launch(z ? k.zorder : k.linear);
        PRT_CUDA_CHECK_LAUNCH();
        return timed;
    }

    void render_wavefront(const core::SceneView& scene, const rt::FrameRequest& req, std::uint32_t w,
                          std::uint32_t h, std::uint32_t y0, std::uint32_t y1) {
        // Primary slots: whole tiles (Z-order) or whole blocks (linear), padding marked k_no_pixel.
        dim3 grid;
        if (!m_options.cuda_linear_mapping) {
            grid = dim3((w + k_tile - 1) / k_tile, (y1 - y0 + k_tile - 1) / k_tile);
        } else {
            const unsigned long long n = static_cast<unsigned long long>(w) * (y1 - y0);
            grid = dim3(static_cast<unsigned>((n + k_block - 1) / k_block));
        }
        const std::uint32_t slots = grid.x * grid.y * k_block;
        const std::uint32_t capacity = 2 * slots;  // each bounce at most doubles; overflow is counted
        m_queue[0].reserve(capacity);
        m_queue[1].reserve(capacity);
        m_hits.reserve(capacity);
        m_accum.reserve(static_cast<std::size_t>(w) * h * 3);
        m_queue_count.reserve(2);
        launch_kernel(launch_grid(grid, k_block, m_stream),
                      m_options.cuda_linear_mapping ? wave_primary<false> : wave_primary<true>, req.camera, w,
                      h, y0, y1, m_queue[0].data(), m_accum.data(), m_counters.data() + k_counters_at);
        const std::uint32_t limit = std::min(req.params.max_bounces, core::k_max_bounces);
        std::uint32_t upper = slots;  // upper bound of the current queue's length
        int cur = 0;
        for (std::uint32_t depth = 0; depth <= limit && upper > 0; ++depth) {
            const std::uint32_t* count = depth == 0 ? nullptr : m_queue_count.data() + cur;
            std::uint32_t* next_count = m_queue_count.data() + (cur ^ 1);
            PRT_CUDA_CHECK(cudaMemsetAsync(next_count, 0, sizeof(std::uint32_t), m_stream));
            const LaunchShape queue = launch_1d(upper, k_block, m_stream);
            launch_kernel(queue, wave_trace, scene, m_queue[cur].data(), count, slots, m_hits.data(),
                          m_counters.data() + k_counters_at);
            launch_kernel(queue, wave_shade, scene, m_queue[cur].data(), count, slots, m_hits.data(),
                          m_queue[cur ^ 1].data(), next_count, capacity, m_accum.data(),
                          m_counters.data() + k_counters_at);
            upper = depth < limit ? std::min<std::uint64_t>(capacity, 2ull * upper) : 0;
            cur ^= 1;
        }
        const unsigned long long n = static_cast<unsigned long long>(w) * (y1 - y0);
        launch_kernel(launch_1d(n, k_block, m_stream), wave_finish, req.params, w, y0, y1, m_accum.data(),
                      m_rgb.data(), rgba_target(req), m_counters.data() + k_counters_at);
    }

    rt::BackendOptions m_options;
    std::uint32_t m_sm_count = 1;
    std::vector<std::pair<RenderKernel, std::uint32_t>> m_resident_blocks;  ///< resident_blocks' answers
    std::string m_device;
    cudaStream_t m_stream = nullptr;
    cudaEvent_t m_start = nullptr, m_stop = nullptr;
    DeviceScene m_device_scene;
    std::uint32_t m_surface_mask = core::k_mask_splats;  ///< surfaces of the scene (core::scene_mask)
    core::SecondaryMaterials m_secondary_materials;      ///< whether its materials reflect, refract
    bool m_shadow_lights = false;                        ///< whether a light casts shadows
    bool m_iso_regions = false;                          ///< whether an ISO model has macro-regions
    rt::WalkChoice m_walk_choice;                        ///< ISO walk per kind of frame (plain_iso_walk)
    core::SceneView m_scene;                             ///< m_device_scene's view
    DeviceBuffer<unsigned long long> m_counters;         ///< [order slot 0, counters, queue, order slot 1]
    DeviceBuffer<std::uint32_t> m_order_heavy[2];        ///< ItemOrder's heavy lists, by frame parity
    DeviceBuffer<std::uint32_t> m_order_stamp;           ///< ItemOrder::stamp
    std::array<std::uint32_t, 4> m_order_shape{};        ///< width, rows, items of the last ordered frame
    std::uint32_t m_order_frame = 0;                     ///< the last ordered frame's number
    DeviceBuffer<float> m_rgb;
    DeviceBuffer<std::uint32_t> m_rgba;
    DeviceBuffer<WaveRay> m_queue[2];
    DeviceBuffer<WaveHit> m_hits;
    DeviceBuffer<float> m_accum;
    DeviceBuffer<std::uint32_t> m_queue_count;
    CastStaging m_staging;  ///< ray batches' device copies (cast.cu)
};

}  // namespace

std::unique_ptr<rt::Backend> make_cuda_backend(const rt::BackendOptions& options) {
    return std::make_unique<CudaBackend>(options);
}

}  // namespace prt::cuda
