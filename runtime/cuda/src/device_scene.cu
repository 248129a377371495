// PointRT CUDA: uploading a scene's arrays (prt/cuda/device_scene.h).
#include <algorithm>
#include <chrono>
#include <cstring>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include "cuda_check.h"
#include "device_buffer.h"
#include "prt/cuda/device_scene.h"
#include "prt/parallel.h"

namespace prt::cuda {

namespace {

/// Copies host arrays to the device through two pinned staging buffers with asynchronous copies,
/// so reading the (memory-mapped) pool overlaps the transfer.
class Uploader {
public:
    explicit Uploader(cudaStream_t stream) : m_stream(stream) {
        for (int i = 0; i < 2; ++i) {
            m_staging[i] = PinnedBuffer(k_chunk);
            PRT_CUDA_CHECK(cudaEventCreateWithFlags(&m_done[i], cudaEventDisableTiming));
        }
    }
    ~Uploader() {
        cudaStreamSynchronize(m_stream);
        for (cudaEvent_t e : m_done) cudaEventDestroy(e);
    }
    Uploader(const Uploader&) = delete;
    Uploader& operator=(const Uploader&) = delete;

    void copy(void* device, const void* host, std::size_t bytes) {
        const auto* src = static_cast<const unsigned char*>(host);
        auto* dst = static_cast<unsigned char*>(device);
        for (std::size_t off = 0; off < bytes; off += k_chunk) {
            const std::size_t n = std::min(k_chunk, bytes - off);
            PRT_CUDA_CHECK(cudaEventSynchronize(m_done[m_next]));  // staging buffer free again
            parallel_copy(static_cast<unsigned char*>(m_staging[m_next].data()), src + off, n);
            PRT_CUDA_CHECK(
                cudaMemcpyAsync(dst + off, m_staging[m_next].data(), n, cudaMemcpyHostToDevice, m_stream));
            PRT_CUDA_CHECK(cudaEventRecord(m_done[m_next], m_stream));
            m_next ^= 1;
        }
        m_bytes += bytes;
    }
    void finish() { PRT_CUDA_CHECK(cudaStreamSynchronize(m_stream)); }

    /// Copies into pinned memory from several threads: reading a memory-mapped pool is bound by
    /// page faults, which parallelise.
    static void parallel_copy(unsigned char* dst, const unsigned char* src, std::size_t n) {
        const unsigned threads = std::min(8u, resolve_threads(0));
        if (n < (4u << 20) || threads == 1) {
            std::memcpy(dst, src, n);
            return;
        }
        parallel_chunks(n, (n + threads - 1) / threads, threads, [=](std::size_t b, std::size_t e, unsigned) {
            std::memcpy(dst + b, src + b, e - b);
        });
    }
    std::uint64_t bytes() const { return m_bytes; }

private:
    static constexpr std::size_t k_chunk = 32u << 20;
    cudaStream_t m_stream;
    PinnedBuffer m_staging[2];
    cudaEvent_t m_done[2] = {nullptr, nullptr};
    int m_next = 0;
    std::uint64_t m_bytes = 0;
};

/// Calls f(field, bytes) for each array pointer of a model (a null or empty one included).
template <class F>
void visit_model_arrays(core::ModelView& mv, F&& f) {
    core::OctreeView& o = mv.octree;
    f(o.nodes, std::size_t{o.node_count} * 4);
    f(o.leaf_info, o.leaf_info ? (std::size_t{o.filled_leaves} + 1) * 4 : 0);
    f(o.splats, std::size_t{o.splat_count} * sizeof(pool::Splat));
    f(o.leaf_bounds, std::size_t{o.filled_leaves} * sizeof(core::LeafBounds));
    f(o.node_boxes, o.node_boxes ? (std::size_t{o.node_count} / 8 + 1) * sizeof(core::NodeBox) : 0);
    f(o.node_box_mask, o.node_box_mask ? std::size_t{o.node_count} / 8 + 1 : 0);
    f(o.macro_regions, o.macro_regions ? std::size_t{o.macro_region_count} * sizeof(core::MacroRegion) : 0);
    // Bricks (issue 17), in core: every brick uploaded, so the resident table and the request
    // flags are dropped (null: every brick at data + offset). Streamed bricks (a host resident
    // table: rt::BrickStream): only the top tree, table, LOD discs and prefixes here; brick data, leaf bounds
    // and the per-brick tables are the brick storage's (cuda_brick_storage.cpp), which sets them.
    core::BrickView& b = mv.bricks;
    const bool streamed = b.resident != nullptr;
    f(b.top_nodes, std::size_t{b.top_node_count} * 4);
    f(b.table, std::size_t{b.brick_count} * sizeof(pool::BrickEntry));
    f(b.data, streamed ? 0 : static_cast<std::size_t>(b.data_bytes));
    f(b.lod, std::size_t{b.top_node_count} * sizeof(pool::LodSplat));
    f(b.lod_table, b.lod_table ? std::size_t{b.brick_count} * sizeof(pool::BrickLod) : 0);
    f(b.lod_nodes, b.lod_nodes ? std::size_t{b.lod_node_count} * 4 : 0);
    f(b.lod_discs, b.lod_discs ? std::size_t{b.lod_node_count} * sizeof(pool::CompressedSplat) : 0);
    // (leaf_bounds' size is read from the host's leaf_bounds_first: that one goes after it)
    const std::size_t brick_leaves =
        b.leaf_bounds_first && !streamed ? b.leaf_bounds_first[b.brick_count] : 0;
    f(b.leaf_bounds, brick_leaves * sizeof(core::BrickLeafBounds));
    f(b.leaf_bounds_first, b.leaf_bounds_first && !streamed ? (std::size_t{b.brick_count} + 1) * 4 : 0);
    f(b.resident, 0);
    f(b.requests, 0);
    f(b.used, 0);
    f(b.prefix_first, 0);  // streamed prefixes: the brick storage's
    f(b.prefix_used, 0);
    core::IsoView& iso = mv.iso;
    f(iso.tree.nodes, std::size_t{iso.tree.node_count} * 4);
    f(iso.tree.macro_regions,
      iso.tree.macro_regions ? std::size_t{iso.tree.macro_region_count} * sizeof(core::MacroRegion) : 0);
    f(iso.leaves_q8, std::size_t{iso.leaf_count} * sizeof(pool::IsoLeafQ8));
    f(iso.leaves_f32, std::size_t{iso.leaf_count} * sizeof(pool::IsoLeafF32));
    core::MlsView& mls = mv.mls;
    f(mls.nodes, std::size_t{mls.node_count} * sizeof(pool::MlsNode));
    f(mls.refs, std::size_t{mls.ref_count} * 4);
    f(mls.splats, std::size_t{mls.splat_count} * sizeof(pool::MlsSplat));
    f(mls.bvh_nodes, std::size_t{mls.bvh_node_count} * sizeof(pool::MlsBvhNode));
    f(mls.bvh_leaves, std::size_t{mls.bvh_leaf_count} * sizeof(pool::MlsBvhLeaf));
    core::PatchView& pv = mv.patches;
    f(pv.nets, std::size_t{pv.patch_count} * sizeof(pool::PatchControlNet));
    f(pv.bvh, std::size_t{pv.bvh_node_count} * sizeof(pool::PatchBvhNode));
    f(pv.nodes, std::size_t{pv.patch_count} * pv.subpatch_nodes * sizeof(pool::SubpatchNode));
    f(mv.colors, std::size_t{mv.point_count} * 4);
    f(mv.material_ids, std::size_t{mv.point_count} * 4);
    for (core::GiOctreeView* gi : {&mv.caustics.tree, &mv.light_map.tree}) {  // thesis 5.3-5.4
        f(gi->nodes, std::size_t{gi->node_count} * 4);
        f(gi->leaves, std::size_t{gi->leaf_count} * sizeof(pool::GiLeaf));
    }
}

/// The same for the scene-wide arrays (models excluded).
template <class F>
void visit_scene_arrays(core::SceneView& s, F&& f) {
    f(s.materials, std::size_t{s.material_count} * sizeof(core::Material));
    f(s.lights, std::size_t{s.light_count} * sizeof(core::PointLight));
    f(s.area_lights, std::size_t{s.area_light_count} * sizeof(core::AreaLight));
    f(s.environment.image, std::size_t{s.environment.width} * s.environment.height * 3 * sizeof(float));
}

std::string mib(std::uint64_t bytes) {
    return std::to_string((bytes + (1u << 20) - 1) >> 20) + " MiB";
}

}  // namespace

struct DeviceScene::Impl {
    core::SceneView view;
    std::vector<DeviceBuffer<unsigned char>> arrays;
    std::vector<core::ModelView> models;       ///< the device models (device pointers), host copy
    core::ModelView* device_models = nullptr;  ///< view.models
};

DeviceScene::DeviceScene() : m(std::make_unique<Impl>()) {}
DeviceScene::~DeviceScene() = default;

const core::SceneView& DeviceScene::view() const {
    return m->view;
}

const core::ModelView& DeviceScene::model(std::uint32_t i) const {
    return m->models.at(i);
}

void DeviceScene::set_model_bricks(std::uint32_t i, const core::BrickView& bricks) {
    m->models.at(i).bricks = bricks;
    PRT_CUDA_CHECK(
        cudaMemcpy(m->device_models + i, &m->models[i], sizeof(core::ModelView), cudaMemcpyHostToDevice));
    // From pageable memory the copy may still be in flight when cudaMemcpy returns, and the
    // renderer's streams do not wait for the default stream: wait here (rare: once per storage).
    PRT_CUDA_CHECK(cudaDeviceSynchronize());
}

std::uint64_t DeviceScene::device_bytes(const core::SceneView& host) {
    std::map<const void*, std::size_t> once;
    auto note = [&](auto* field, std::size_t bytes) {
        if (field != nullptr && bytes > 0) once.emplace(field, bytes);
    };
    std::vector<core::ModelView> models(host.models, host.models + host.model_count);
    for (core::ModelView& mv : models) visit_model_arrays(mv, note);
    core::SceneView s = host;
    visit_scene_arrays(s, note);
    std::uint64_t total = models.size() * sizeof(core::ModelView);
    for (const auto& entry : once) total += entry.second;
    return total;
}

rt::UploadStats DeviceScene::upload(const core::SceneView& host, cudaStream_t stream) {
    const auto start = std::chrono::steady_clock::now();
    m->arrays.clear();
    m->view = core::SceneView{};
    m->models.clear();
    m->device_models = nullptr;
    // Issue 10: a pool larger than the GPU's free memory fails up front, with the figures.
    const std::uint64_t need = device_bytes(host);
    std::size_t free_bytes = 0, total_bytes = 0;
    PRT_CUDA_CHECK(cudaMemGetInfo(&free_bytes, &total_bytes));
    const std::uint64_t reserve = 256ull << 20;  // frame buffers, ray queues, the driver's own
    if (need + reserve > free_bytes) {
        throw Error(
            "the scene needs " + mib(need) + " on the GPU (+ " + mib(reserve) + " for frames) but only " +
            mib(free_bytes) + " of " + mib(total_bytes) +
            " are free: build a coarser ISO (prt-iso --max-level), cull the splats (prt-cull), or render "
            "with --backend cpu");
    }
    std::map<const void*, void*> uploaded;  // the same pool array used by several models: once
    Uploader up(stream);
    auto put = [&](const void* src, std::size_t bytes) -> void* {
        if (src == nullptr || bytes == 0) return nullptr;
        auto it = uploaded.find(src);
        if (it != uploaded.end()) return it->second;
        DeviceBuffer<unsigned char> buf(bytes);
        up.copy(buf.data(), src, bytes);
        void* d = buf.data();
        m->arrays.push_back(std::move(buf));
        uploaded[src] = d;
        return d;
    };
    auto put_as = [&](auto*& field, std::size_t bytes) {
        using T = std::remove_pointer_t<std::remove_reference_t<decltype(field)>>;
        field = static_cast<T*>(put(field, bytes));
    };
    std::vector<core::ModelView> models(host.models, host.models + host.model_count);
    for (core::ModelView& mv : models) visit_model_arrays(mv, put_as);
    core::SceneView& s = m->view;
    s = host;
    visit_scene_arrays(s, put_as);
    m->device_models =
        static_cast<core::ModelView*>(put(models.data(), models.size() * sizeof(core::ModelView)));
    s.models = m->device_models;
    up.finish();  // `models` (host) must outlive the copies
    m->models = std::move(models);
    rt::UploadStats stats;
    stats.bytes = up.bytes();
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return stats;
}

}  // namespace prt::cuda
