// PointRT CUDA backend: a move-only RAII device allocation (tiny-cuda-nn's GPUMemory idea: copies
// happen only when asked for explicitly, to prevent performance accidents). Host-only header.
#pragma once

#include <cuda_runtime.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <mutex>
#include <utility>

#include "cuda_check.h"

namespace prt::cuda {

template <class T>
class DeviceBuffer {
public:
    DeviceBuffer() = default;
    explicit DeviceBuffer(std::size_t count) { resize(count); }
    ~DeviceBuffer() { release(); }
    DeviceBuffer(const DeviceBuffer&) = delete;
    DeviceBuffer& operator=(const DeviceBuffer&) = delete;
    DeviceBuffer(DeviceBuffer&& o) noexcept
        : m_data(std::exchange(o.m_data, nullptr)), m_count(std::exchange(o.m_count, 0)) {}
    DeviceBuffer& operator=(DeviceBuffer&& o) noexcept {
        if (this != &o) {
            release();
            m_data = std::exchange(o.m_data, nullptr);
            m_count = std::exchange(o.m_count, 0);
        }
        return *this;
    }

    /// Reallocates to exactly `count` elements (contents are not kept).
    void resize(std::size_t count) {
        if (count == m_count) return;
        release();
        if (count > 0) {
            void* p = nullptr;
            PRT_CUDA_CHECK(cudaMalloc(&p, count * sizeof(T)));
            m_data = static_cast<T*>(p);
            m_count = count;
        }
    }
    /// Grows to at least `count` elements (contents are not kept).
    void reserve(std::size_t count) {
        if (count > m_count) resize(count);
    }
    void release() noexcept {
        if (m_data) cudaFree(m_data);  // no throw from a destructor path
        m_data = nullptr;
        m_count = 0;
    }
    void upload(const T* host, std::size_t count, cudaStream_t stream = nullptr) {
        reserve(count);
        if (count)
            PRT_CUDA_CHECK(cudaMemcpyAsync(m_data, host, count * sizeof(T), cudaMemcpyHostToDevice, stream));
    }
    void download(T* host, std::size_t count, std::size_t offset = 0, cudaStream_t stream = nullptr) const {
        if (count)
            PRT_CUDA_CHECK(
                cudaMemcpyAsync(host, m_data + offset, count * sizeof(T), cudaMemcpyDeviceToHost, stream));
    }
    T* data() const { return m_data; }
    std::size_t size() const { return m_count; }
    std::size_t bytes() const { return m_count * sizeof(T); }

private:
    T* m_data = nullptr;
    std::size_t m_count = 0;
};

/// Move-only pinned (page-locked) host memory for asynchronous copies.
class PinnedBuffer {
public:
    PinnedBuffer() = default;
    explicit PinnedBuffer(std::size_t bytes) {
        PRT_CUDA_CHECK(cudaMallocHost(&m_data, bytes));
        m_bytes = bytes;
    }
    ~PinnedBuffer() {
        if (m_data) cudaFreeHost(m_data);
    }
    PinnedBuffer(const PinnedBuffer&) = delete;
    PinnedBuffer& operator=(const PinnedBuffer&) = delete;
    PinnedBuffer(PinnedBuffer&& o) noexcept
        : m_data(std::exchange(o.m_data, nullptr)), m_bytes(std::exchange(o.m_bytes, 0)) {}
    PinnedBuffer& operator=(PinnedBuffer&& o) noexcept {
        if (this != &o) {
            if (m_data) cudaFreeHost(m_data);
            m_data = std::exchange(o.m_data, nullptr);
            m_bytes = std::exchange(o.m_bytes, 0);
        }
        return *this;
    }
    void* data() const { return m_data; }
    std::size_t bytes() const { return m_bytes; }

private:
    void* m_data = nullptr;
    std::size_t m_bytes = 0;
};

/// Copies between pageable host memory and the device through two page-locked chunks of the
/// calling thread, double buffered: a copy from or to pageable memory goes through the driver's
/// own staging (an octree's splats came down at 1.4 GB/s on the H200 host, and the out-of-core
/// build's cell workers copy side by side). Copies are complete when these return.
class Staging {
public:
    static constexpr std::size_t k_chunk = std::size_t{8} << 20;

    static Staging& local() {
        thread_local Staging staging;
        return staging;
    }
    ~Staging() {
        for (cudaEvent_t e : m_done)
            if (e) cudaEventDestroy(e);
    }
    Staging(const Staging&) = delete;
    Staging& operator=(const Staging&) = delete;

    void to_device(void* dst, const void* src, std::size_t bytes, cudaStream_t stream) {
        ready();
        for (std::size_t off = 0, i = 0; off < bytes; off += k_chunk, ++i) {
            const std::size_t n = bytes - off < k_chunk ? bytes - off : k_chunk;
            const int slot = static_cast<int>(i & 1u);
            PRT_CUDA_CHECK(cudaEventSynchronize(m_done[slot]));  // the slot's last copy is done
            std::memcpy(m_chunk[slot].data(), static_cast<const char*>(src) + off, n);
            PRT_CUDA_CHECK(cudaMemcpyAsync(static_cast<char*>(dst) + off, m_chunk[slot].data(), n,
                                           cudaMemcpyHostToDevice, stream));
            PRT_CUDA_CHECK(cudaEventRecord(m_done[slot], stream));
        }
        PRT_CUDA_CHECK(cudaEventSynchronize(m_done[0]));
        PRT_CUDA_CHECK(cudaEventSynchronize(m_done[1]));
    }

    void to_host(void* dst, const void* src, std::size_t bytes, cudaStream_t stream) {
        ready();
        std::size_t pending_off = 0, pending_n = 0;
        int pending_slot = 0;
        for (std::size_t off = 0, i = 0; off < bytes; off += k_chunk, ++i) {
            const std::size_t n = bytes - off < k_chunk ? bytes - off : k_chunk;
            const int slot = static_cast<int>(i & 1u);
            PRT_CUDA_CHECK(cudaMemcpyAsync(m_chunk[slot].data(), static_cast<const char*>(src) + off, n,
                                           cudaMemcpyDeviceToHost, stream));
            PRT_CUDA_CHECK(cudaEventRecord(m_done[slot], stream));
            if (pending_n) drain(dst, pending_off, pending_n, pending_slot);  // beside this chunk's copy
            pending_off = off;
            pending_n = n;
            pending_slot = slot;
        }
        if (pending_n) drain(dst, pending_off, pending_n, pending_slot);
    }

private:
    Staging() = default;
    void ready() {
        if (m_done[0]) return;
        for (int k = 0; k < 2; ++k) {
            m_chunk[k] = PinnedBuffer(k_chunk);
            PRT_CUDA_CHECK(cudaEventCreateWithFlags(&m_done[k], cudaEventDisableTiming));
        }
    }
    void drain(void* dst, std::size_t off, std::size_t n, int slot) {
        PRT_CUDA_CHECK(cudaEventSynchronize(m_done[slot]));
        std::memcpy(static_cast<char*>(dst) + off, m_chunk[slot].data(), n);
    }
    PinnedBuffer m_chunk[2];
    cudaEvent_t m_done[2] = {nullptr, nullptr};
};

/// `bytes` from pageable host memory to the device on `stream`: staged (Staging) from one chunk up,
/// and then done on return.
inline void copy_to_device(void* dst, const void* src, std::size_t bytes, cudaStream_t stream) {
    if (bytes >= Staging::k_chunk)
        Staging::local().to_device(dst, src, bytes, stream);
    else if (bytes)
        PRT_CUDA_CHECK(cudaMemcpyAsync(dst, src, bytes, cudaMemcpyHostToDevice, stream));
}

/// `bytes` from the device to pageable host memory on `stream`, after the stream's earlier work:
/// staged (Staging) from one chunk up, and then done on return; else at the stream's next wait.
inline void copy_to_host(void* dst, const void* src, std::size_t bytes, cudaStream_t stream) {
    if (bytes >= Staging::k_chunk)
        Staging::local().to_host(dst, src, bytes, stream);
    else if (bytes)
        PRT_CUDA_CHECK(cudaMemcpyAsync(dst, src, bytes, cudaMemcpyDeviceToHost, stream));
}

/// Device memory from the stream-ordered pool (cudaMallocAsync) on one stream: for work that runs
/// beside other threads' (the out-of-core build's cell workers build and cull side by side), where
/// DeviceBuffer's cudaFree would wait for all of it (it synchronizes the device). Freed blocks stay
/// in the pool (keep_pool_memory) for the next user.
template <class T>
class AsyncBuffer {
public:
    explicit AsyncBuffer(cudaStream_t stream = nullptr) : m_stream(stream) {}
    ~AsyncBuffer() { release(); }
    AsyncBuffer(const AsyncBuffer&) = delete;
    AsyncBuffer& operator=(const AsyncBuffer&) = delete;
    AsyncBuffer(AsyncBuffer&& o) noexcept
        : m_data(std::exchange(o.m_data, nullptr)),
          m_count(std::exchange(o.m_count, 0)),
          m_stream(o.m_stream) {}
    AsyncBuffer& operator=(AsyncBuffer&& o) noexcept {
        if (this != &o) {
            release();
            m_data = std::exchange(o.m_data, nullptr);
            m_count = std::exchange(o.m_count, 0);
            m_stream = o.m_stream;
        }
        return *this;
    }
    /// Exactly `count` elements (contents not kept).
    void resize(std::size_t count) {
        if (count == m_count) return;
        release();
        if (count > 0) {
            void* p = nullptr;
            PRT_CUDA_CHECK(cudaMallocAsync(&p, count * sizeof(T), m_stream));
            m_data = static_cast<T*>(p);
            m_count = count;
        }
    }
    /// At least `count` elements (contents not kept).
    void reserve(std::size_t count) {
        if (count > m_count) resize(count);
    }
    void release() noexcept {
        if (m_data) cudaFreeAsync(m_data, m_stream);
        m_data = nullptr;
        m_count = 0;
    }
    /// Copies `count` elements of pageable host memory in (copy_to_device: staged when large).
    void upload(const T* host, std::size_t count) {
        reserve(count);
        copy_to_device(m_data, host, count * sizeof(T), m_stream);
    }
    /// Copies `count` elements out to pageable host memory after the stream's earlier work
    /// (copy_to_host: staged and done on return when large; else at the stream's next wait).
    void download(T* host, std::size_t count) const {
        copy_to_host(host, m_data, count * sizeof(T), m_stream);
    }
    T* data() const { return m_data; }
    std::size_t bytes() const { return m_count * sizeof(T); }

private:
    T* m_data = nullptr;
    std::size_t m_count = 0;
    cudaStream_t m_stream = nullptr;
};

/// Keeps freed blocks in device 0's stream-ordered pool instead of returning them at every
/// synchronization (the default threshold is 0), once per process.
inline void keep_pool_memory() {
    static std::once_flag once;
    std::call_once(once, [] {
        cudaMemPool_t pool = nullptr;
        if (cudaDeviceGetDefaultMemPool(&pool, 0) != cudaSuccess) return;
        std::uint64_t threshold = ~std::uint64_t{0};
        cudaMemPoolSetAttribute(pool, cudaMemPoolAttrReleaseThreshold, &threshold);
    });
}

/// A non-blocking stream of its own (no implicit synchronization with the legacy default stream).
class OwnedStream {
public:
    OwnedStream() { PRT_CUDA_CHECK(cudaStreamCreateWithFlags(&m_stream, cudaStreamNonBlocking)); }
    ~OwnedStream() {
        if (m_stream) cudaStreamDestroy(m_stream);
    }
    OwnedStream(const OwnedStream&) = delete;
    OwnedStream& operator=(const OwnedStream&) = delete;
    cudaStream_t get() const { return m_stream; }

private:
    cudaStream_t m_stream = nullptr;
};

}  // namespace prt::cuda
