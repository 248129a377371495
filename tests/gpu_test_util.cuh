// Test-only helpers for the CUDA kernel tests (label gpu): a checked CUDA call that fails the
// test, device buffers freed with the test, and whether a device exists. Include from .cu files.
#pragma once

#include <cuda_runtime.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

/// Fails the current test (ASSERT) with the call, place and CUDA error string.
#define PRT_CUDA_CHECK(call)                                                                          \
    do {                                                                                              \
        const cudaError_t prt_err = (call);                                                           \
        ASSERT_EQ(prt_err, cudaSuccess)                                                               \
            << #call << " at " << __FILE__ << ":" << __LINE__ << ": " << cudaGetErrorString(prt_err); \
    } while (0)

namespace prt::test {

/// Device allocations freed on destruction; null on failure (tests check what they get).
struct DeviceBuffers {
    std::vector<void*> buffers;
    DeviceBuffers() = default;
    DeviceBuffers(const DeviceBuffers&) = delete;
    DeviceBuffers& operator=(const DeviceBuffers&) = delete;
    ~DeviceBuffers() {
        for (void* b : buffers) cudaFree(b);
    }
    template <class T>
    T* alloc(std::size_t count) {
        void* p = nullptr;
        if (cudaMalloc(&p, std::max<std::size_t>(count, 1) * sizeof(T)) != cudaSuccess) return nullptr;
        buffers.push_back(p);
        return static_cast<T*>(p);
    }
    template <class T>
    T* upload(const T* host, std::size_t count) {
        T* p = alloc<T>(count);
        if (p && cudaMemcpy(p, host, count * sizeof(T), cudaMemcpyHostToDevice) != cudaSuccess)
            return nullptr;
        return p;
    }
};

/// Whether a CUDA device can be used; `why` says why not.
inline bool have_device(std::string& why) {
    int count = 0;
    const cudaError_t e = cudaGetDeviceCount(&count);
    if (e != cudaSuccess || count == 0) {
        why = std::string("no CUDA device: ") + (e != cudaSuccess ? cudaGetErrorString(e) : "none found");
        return false;
    }
    return true;
}

}  // namespace prt::test
