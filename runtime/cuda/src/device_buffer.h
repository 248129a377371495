// PointRT CUDA backend: a move-only RAII device allocation (tiny-cuda-nn's GPUMemory idea: copies
// happen only when asked for explicitly, to prevent performance accidents). Host-only header.
#pragma once

#include <cuda_runtime.h>

#include <cstddef>
#include <cstdint>
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
    void upload(const T* host, std::size_t count) {
        reserve(count);
        if (count)
            PRT_CUDA_CHECK(
                cudaMemcpyAsync(m_data, host, count * sizeof(T), cudaMemcpyHostToDevice, m_stream));
    }
    void download(T* host, std::size_t count) const {
        if (count)
            PRT_CUDA_CHECK(
                cudaMemcpyAsync(host, m_data, count * sizeof(T), cudaMemcpyDeviceToHost, m_stream));
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
