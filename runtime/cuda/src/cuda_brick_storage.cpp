// PointRT CUDA: streamed bricks' storage on the GPU (rt::BrickStorage, prt/runtime/brick_stream.h):
// a device arena for payloads and leaf bounds, filled through pinned staging memory with
// asynchronous copies on a copy stream of its own; the resident table, first leaf bounds and the
// use / request flags on the device, their host mirrors pinned. Host code over the CUDA runtime.
#include "cuda_brick_storage.h"

#include <algorithm>
#include <cstring>
#include <vector>

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
        m_flags = DeviceBuffer<std::uint32_t>(std::max<std::size_t>(2 * std::size_t{m_bricks}, 1));
        PRT_CUDA_CHECK(cudaMemset(m_resident.data(), 0, m_resident.size() * sizeof(unsigned long long)));
        PRT_CUDA_CHECK(cudaMemset(m_first.data(), 0, m_first.size() * 4));
        PRT_CUDA_CHECK(cudaMemset(m_flags.data(), 0, m_flags.size() * 4));
        m_host_resident = PinnedBuffer(m_resident.size() * sizeof(unsigned long long));
        m_host_first = PinnedBuffer(m_first.size() * 4);
        m_host_flags = PinnedBuffer(m_flags.size() * 4);
        std::memset(m_host_resident.data(), 0, m_resident.size() * sizeof(unsigned long long));
        std::memset(m_host_first.data(), 0, m_first.size() * 4);
        m_staging = PinnedBuffer(k_staging);
        reattach();
    }
    ~CudaBrickStorage() override {
        if (m_copy) {
            cudaStreamSynchronize(m_copy);
            cudaStreamDestroy(m_copy);
        }
    }
    CudaBrickStorage(const CudaBrickStorage&) = delete;
    CudaBrickStorage& operator=(const CudaBrickStorage&) = delete;

    void upload(std::uint64_t offset, std::span<const unsigned char> payload, std::uint64_t bounds_offset,
                std::span<const core::LeafBounds> bounds) override {
        stage(m_arena.data() + offset, payload.data(), payload.size());
        stage(m_arena.data() + bounds_offset, reinterpret_cast<const unsigned char*>(bounds.data()),
              bounds.size_bytes());
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
    void commit() override {
        if (m_dirty) {
            PRT_CUDA_CHECK(cudaMemcpyAsync(m_resident.data(), m_host_resident.data(),
                                           m_resident.size() * sizeof(unsigned long long),
                                           cudaMemcpyHostToDevice, m_copy));
            PRT_CUDA_CHECK(cudaMemcpyAsync(m_first.data(), m_host_first.data(), m_first.size() * 4,
                                           cudaMemcpyHostToDevice, m_copy));
            m_dirty = false;
        }
        PRT_CUDA_CHECK(cudaStreamSynchronize(m_copy));  // the next frame reads what was copied
        m_staged = 0;
    }
    void take_flags(std::vector<std::uint32_t>& used, std::vector<std::uint32_t>& requested) override {
        // The frame's kernels finished (the backend's render() waits for its stream).
        PRT_CUDA_CHECK(cudaMemcpyAsync(m_host_flags.data(), m_flags.data(), m_flags.size() * 4,
                                       cudaMemcpyDeviceToHost, m_copy));
        PRT_CUDA_CHECK(cudaMemsetAsync(m_flags.data(), 0, m_flags.size() * 4, m_copy));
        PRT_CUDA_CHECK(cudaStreamSynchronize(m_copy));
        const auto* flags = static_cast<const std::uint32_t*>(m_host_flags.data());
        used.assign(flags, flags + m_bricks);
        requested.assign(flags + m_bricks, flags + 2 * std::size_t{m_bricks});
    }

    /// Points the device model's brick view at this storage: the scene's device top tree, table
    /// and LOD (new addresses after each upload of the scene), this storage's arena and tables.
    void reattach() override {
        core::BrickView v = m_scene.model(m_model).bricks;
        v.data = nullptr;
        v.data_bytes = 0;
        v.resident = reinterpret_cast<const unsigned char* const*>(m_resident.data());
        v.leaf_bounds = reinterpret_cast<const core::LeafBounds*>(m_arena.data());
        v.leaf_bounds_first = m_first.data();
        v.used = m_flags.data();
        v.requests = m_flags.data() + m_bricks;
        m_scene.set_model_bricks(m_model, v);
    }

private:
    static constexpr std::size_t k_staging = 64u << 20;

    /// Copies host bytes to the device through the staging buffer; when it is full, waits for the
    /// copies in flight and starts again at its beginning.
    void stage(unsigned char* device, const unsigned char* host, std::size_t bytes) {
        for (std::size_t done = 0; done < bytes;) {
            if (m_staged >= k_staging) {
                PRT_CUDA_CHECK(cudaStreamSynchronize(m_copy));
                m_staged = 0;
            }
            const std::size_t n = std::min(bytes - done, k_staging - m_staged);
            unsigned char* staging = static_cast<unsigned char*>(m_staging.data()) + m_staged;
            std::memcpy(staging, host + done, n);
            PRT_CUDA_CHECK(cudaMemcpyAsync(device + done, staging, n, cudaMemcpyHostToDevice, m_copy));
            m_staged += (n + 255) / 256 * 256;
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
    DeviceBuffer<std::uint32_t> m_flags;  ///< used, then requested: brick_count each
    PinnedBuffer m_host_resident, m_host_first, m_host_flags, m_staging;
    std::size_t m_staged = 0;
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
