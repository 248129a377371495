// PointRT CUDA: streamed bricks' storage on the GPU (rt::BrickStorage, prt/runtime/brick_stream.h):
// a device arena for payloads and leaf bounds, filled through pinned staging memory with
// asynchronous copies on a copy stream of its own (a ring of staging slots: the host fills one while
// the copies of the others run); the leaf bounds derived from the payloads on the GPU after the
// copies (brick_bounds.h); the resident table, first leaf bounds and the use / request flags on the
// device, their host mirrors pinned. Host code over the CUDA runtime.
#include "cuda_brick_storage.h"

#include <algorithm>
#include <cstring>
#include <vector>

#include "brick_bounds.h"
#include "cuda_check.h"
#include "device_buffer.h"
#include "prt/runtime/brick_stream.h"

namespace prt::cuda {

namespace {

class CudaBrickStorage final : public rt::BrickStorage {
public:
    CudaBrickStorage(DeviceScene& scene, std::uint32_t model, const rt::BrickArena& a)
        : m_scene(scene), m_model(model), m_bricks(a.brick_count) {
        PRT_CUDA_CHECK(cudaStreamCreateWithFlags(&m_copy, cudaStreamNonBlocking));
        m_arena = DeviceBuffer<unsigned char>(static_cast<std::size_t>(std::max<std::uint64_t>(a.bytes, 64)));
        m_resident = DeviceBuffer<unsigned long long>(std::max<std::size_t>(m_bricks, 1));
        m_first = DeviceBuffer<std::uint32_t>(std::size_t{m_bricks} + 1);
        m_prefixes = a.streams_prefixes;
        m_flags =
            DeviceBuffer<std::uint32_t>(std::max<std::size_t>(flag_arrays() * std::size_t{m_bricks}, 1));
        PRT_CUDA_CHECK(cudaMemset(m_resident.data(), 0, m_resident.size() * sizeof(unsigned long long)));
        PRT_CUDA_CHECK(cudaMemset(m_first.data(), 0, m_first.size() * 4));
        PRT_CUDA_CHECK(cudaMemset(m_flags.data(), 0, m_flags.size() * 4));
        m_host_resident = PinnedBuffer(m_resident.size() * sizeof(unsigned long long));
        m_host_first = PinnedBuffer(m_first.size() * 4);
        m_host_flags = PinnedBuffer(m_flags.size() * 4);
        std::memset(m_host_resident.data(), 0, m_resident.size() * sizeof(unsigned long long));
        std::memset(m_host_first.data(), 0, m_first.size() * 4);
        if (m_prefixes) {  // every prefix missing at first
            m_prefix_first = DeviceBuffer<std::uint32_t>(std::max<std::size_t>(m_bricks, 1));
            m_host_prefix_first = PinnedBuffer(m_prefix_first.size() * 4);
            std::fill_n(static_cast<std::uint32_t*>(m_host_prefix_first.data()), m_prefix_first.size(),
                        core::k_prefix_missing);
            PRT_CUDA_CHECK(cudaMemcpy(m_prefix_first.data(), m_host_prefix_first.data(),
                                      m_prefix_first.size() * 4, cudaMemcpyHostToDevice));
        }
        m_staging = PinnedBuffer(k_slots * k_slot);
        for (cudaEvent_t& e : m_slot_done)
            PRT_CUDA_CHECK(cudaEventCreateWithFlags(&e, cudaEventDisableTiming));
        reattach();
    }
    ~CudaBrickStorage() override {
        if (m_copy) {
            cudaStreamSynchronize(m_copy);
            cudaStreamDestroy(m_copy);
        }
        for (cudaEvent_t e : m_slot_done)
            if (e) cudaEventDestroy(e);
    }
    CudaBrickStorage(const CudaBrickStorage&) = delete;
    CudaBrickStorage& operator=(const CudaBrickStorage&) = delete;

    bool derives_leaf_bounds() const override { return true; }
    void upload(std::uint64_t offset, std::span<const unsigned char> payload, std::uint64_t bounds_offset,
                std::span<const core::BrickLeafBounds> bounds) override {
        stage(m_arena.data() + offset, payload.data(), payload.size());
        if (!bounds.empty()) {
            stage(m_arena.data() + bounds_offset, reinterpret_cast<const unsigned char*>(bounds.data()),
                  bounds.size_bytes());
            return;
        }
        // Derived on the device at commit(), from the payload once its copy has run.
        pool::BrickHeader h;
        std::memcpy(&h, payload.data(), sizeof(h));  // a validated payload (BrickStream checks it first)
        m_jobs.push_back(BrickBoundsJob{
            m_arena.data() + offset, reinterpret_cast<core::BrickLeafBounds*>(m_arena.data() + bounds_offset),
            m_job_leaves, h.leaf_count});
        m_job_leaves += h.leaf_count;
    }
    void set_resident(std::uint32_t brick, std::uint64_t offset, std::uint32_t first_bound) override {
        auto* resident = static_cast<unsigned long long*>(m_host_resident.data());
        auto* first = static_cast<std::uint32_t*>(m_host_first.data());
        resident[brick] =
            offset == k_not_resident
                ? 0ull
                : static_cast<unsigned long long>(reinterpret_cast<std::uintptr_t>(m_arena.data() + offset));
        first[brick] = offset == k_not_resident ? 0u : first_bound;
        m_dirty = true;
    }
    void upload_prefix(std::uint64_t offset, std::span<const std::uint32_t> nodes,
                       std::span<const pool::CompressedSplat> discs) override {
        const auto count = static_cast<std::uint32_t>(nodes.size());  // staged (copied) at once
        stage(m_arena.data() + offset, reinterpret_cast<const unsigned char*>(&count), sizeof(count));
        stage(m_arena.data() + offset + sizeof(count), reinterpret_cast<const unsigned char*>(nodes.data()),
              nodes.size_bytes());
        stage(m_arena.data() + offset + sizeof(count) + nodes.size_bytes(),
              reinterpret_cast<const unsigned char*>(discs.data()), discs.size_bytes());
    }
    void set_prefix(std::uint32_t brick, std::uint64_t offset) override {
        static_cast<std::uint32_t*>(m_host_prefix_first.data())[brick] = prefix_first(offset);
        m_dirty = true;
    }
    void commit() override {
        if (!m_jobs.empty()) {
            if (m_job_capacity < m_jobs.size()) {  // the copy stream is idle here (commit waits for it)
                m_job_capacity = std::max<std::size_t>(m_jobs.size(), 2 * m_job_capacity);
                m_device_jobs = DeviceBuffer<BrickBoundsJob>(m_job_capacity);
                m_host_jobs = PinnedBuffer(m_job_capacity * sizeof(BrickBoundsJob));
            }
            std::memcpy(m_host_jobs.data(), m_jobs.data(), m_jobs.size() * sizeof(BrickBoundsJob));
            PRT_CUDA_CHECK(cudaMemcpyAsync(m_device_jobs.data(), m_host_jobs.data(),
                                           m_jobs.size() * sizeof(BrickBoundsJob), cudaMemcpyHostToDevice,
                                           m_copy));
            derive_brick_leaf_bounds(m_device_jobs.data(), static_cast<std::uint32_t>(m_jobs.size()),
                                     m_job_leaves, m_copy);
            m_jobs.clear();
            m_job_leaves = 0;
        }
        if (m_dirty) {
            PRT_CUDA_CHECK(cudaMemcpyAsync(m_resident.data(), m_host_resident.data(),
                                           m_resident.size() * sizeof(unsigned long long),
                                           cudaMemcpyHostToDevice, m_copy));
            PRT_CUDA_CHECK(cudaMemcpyAsync(m_first.data(), m_host_first.data(), m_first.size() * 4,
                                           cudaMemcpyHostToDevice, m_copy));
            if (m_prefixes)
                PRT_CUDA_CHECK(cudaMemcpyAsync(m_prefix_first.data(), m_host_prefix_first.data(),
                                               m_prefix_first.size() * 4, cudaMemcpyHostToDevice, m_copy));
            m_dirty = false;
        }
        PRT_CUDA_CHECK(cudaStreamSynchronize(m_copy));  // the next frame reads what was copied
        m_slot_used = 0;                                // every slot's copies are done
    }
    void take_flags(std::vector<std::uint32_t>& used, std::vector<std::uint32_t>& requested,
                    std::vector<std::uint32_t>& prefix_used) override {
        // The frame's kernels finished (the backend's render() waits for its stream).
        PRT_CUDA_CHECK(cudaMemcpyAsync(m_host_flags.data(), m_flags.data(), m_flags.size() * 4,
                                       cudaMemcpyDeviceToHost, m_copy));
        PRT_CUDA_CHECK(cudaMemsetAsync(m_flags.data(), 0, m_flags.size() * 4, m_copy));
        PRT_CUDA_CHECK(cudaStreamSynchronize(m_copy));
        const auto* flags = static_cast<const std::uint32_t*>(m_host_flags.data());
        used.assign(flags, flags + m_bricks);
        requested.assign(flags + m_bricks, flags + 2 * std::size_t{m_bricks});
        if (m_prefixes)
            prefix_used.assign(flags + 2 * std::size_t{m_bricks}, flags + 3 * std::size_t{m_bricks});
        else
            prefix_used.assign(m_bricks, 0u);
    }

    /// Points the device model's brick view at this storage: the scene's device top tree, table
    /// and LOD (new addresses after each upload of the scene), this storage's arena and tables.
    void reattach() override {
        core::BrickView v = m_scene.model(m_model).bricks;
        v.data = nullptr;
        v.data_bytes = 0;
        v.resident = reinterpret_cast<const unsigned char* const*>(m_resident.data());
        v.leaf_bounds = reinterpret_cast<const core::BrickLeafBounds*>(m_arena.data());
        v.leaf_bounds_first = m_first.data();
        v.used = m_flags.data();
        v.requests = m_flags.data() + m_bricks;
        if (m_prefixes) {  // streamed prefixes: blocks of the arena, words from its start
            v.lod_nodes = reinterpret_cast<const std::uint32_t*>(m_arena.data());
            v.lod_discs = nullptr;
            v.lod_node_count = 0;
            v.prefix_first = m_prefix_first.data();
            v.prefix_used = m_flags.data() + 2 * std::size_t{m_bricks};
        }
        m_scene.set_model_bricks(m_model, v);
    }

private:
    static constexpr std::size_t k_slots = 4, k_slot = 16u << 20;
    /// Flag arrays of brick_count words: used, requested and, with streamed prefixes, prefix_used.
    std::size_t flag_arrays() const { return m_prefixes ? 3 : 2; }

    /// Copies host bytes to the device through the staging ring: each piece is copied into the
    /// current slot and its asynchronous copy queued at once; a full slot is closed with an event,
    /// and the next slot is reused once its own earlier copies have finished.
    void stage(unsigned char* device, const unsigned char* host, std::size_t bytes) {
        for (std::size_t done = 0; done < bytes;) {
            if (m_slot_used >= k_slot) {
                PRT_CUDA_CHECK(cudaEventRecord(m_slot_done[m_slot], m_copy));
                m_slot = (m_slot + 1) % k_slots;
                PRT_CUDA_CHECK(cudaEventSynchronize(m_slot_done[m_slot]));
                m_slot_used = 0;
            }
            const std::size_t n = std::min(bytes - done, k_slot - m_slot_used);
            unsigned char* staging =
                static_cast<unsigned char*>(m_staging.data()) + m_slot * k_slot + m_slot_used;
            std::memcpy(staging, host + done, n);
            PRT_CUDA_CHECK(cudaMemcpyAsync(device + done, staging, n, cudaMemcpyHostToDevice, m_copy));
            m_slot_used += (n + 255) / 256 * 256;
            done += n;
        }
    }

    DeviceScene& m_scene;
    std::uint32_t m_model;
    std::uint32_t m_bricks;
    cudaStream_t m_copy = nullptr;
    DeviceBuffer<unsigned char> m_arena;
    DeviceBuffer<unsigned long long> m_resident;  ///< const unsigned char* per brick
    DeviceBuffer<std::uint32_t> m_first;
    DeviceBuffer<std::uint32_t> m_flags;  ///< used, requested (then prefix_used): brick_count each
    bool m_prefixes = false;              ///< LOD prefixes stream into the arena
    DeviceBuffer<std::uint32_t> m_prefix_first;
    PinnedBuffer m_host_resident, m_host_first, m_host_flags, m_staging, m_host_prefix_first;
    cudaEvent_t m_slot_done[k_slots] = {};
    std::size_t m_slot = 0, m_slot_used = 0;
    std::vector<BrickBoundsJob> m_jobs;  ///< this frame's uploads whose bounds the device derives
    std::uint32_t m_job_leaves = 0;
    std::size_t m_job_capacity = 0;
    DeviceBuffer<BrickBoundsJob> m_device_jobs;
    PinnedBuffer m_host_jobs;
    bool m_dirty = false;
};

}  // namespace

std::unique_ptr<rt::BrickStorage> make_cuda_brick_storage(DeviceScene& scene, std::uint32_t model,
                                                          const rt::BrickArena& arena) {
    return std::make_unique<CudaBrickStorage>(scene, model, arena);
}

std::uint64_t default_memory_budget() {
    std::size_t free_bytes = 0, total_bytes = 0;
    PRT_CUDA_CHECK(cudaMemGetInfo(&free_bytes, &total_bytes));
    const std::uint64_t margin = 512ull << 20;  // frame buffers, ray queues, staging, the driver's own
    return free_bytes > margin ? free_bytes - margin : 1;
}

}  // namespace prt::cuda
