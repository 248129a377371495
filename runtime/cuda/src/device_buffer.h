// PointRT CUDA backend: a move-only RAII device allocation (tiny-cuda-nn's GPUMemory idea: copies
// happen only when asked for explicitly, to prevent performance accidents). Host-only header.
#pragma once

#include <cuda_runtime.h>

#include <cstddef>
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

}  // namespace prt::cuda
