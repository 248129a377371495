// Test-only helpers for the CUDA kernel tests (label gpu): a checked CUDA call that fails the
// test, device buffers freed with the test, and whether a device exists. Include from .cu files.
#pragma once

#include <cuda_runtime.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "prt/core/ray.h"

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

/// Copies `count` elements from the device into `out` (resized).
template <class T>
cudaError_t download(std::vector<T>& out, const T* device, std::size_t count) {
    out.resize(count);
    return cudaMemcpy(out.data(), device, count * sizeof(T), cudaMemcpyDeviceToHost);
}

/// Launches a kernel through `launch` `reps` times, each between two CUDA events (the caller has
/// run a warm-up), and returns the per-launch milliseconds in `ms`, sorted (ms[reps / 2] is the
/// median).
template <class Launch>
cudaError_t time_launches(int reps, Launch&& launch, std::vector<float>& ms) {
    cudaEvent_t start = nullptr, stop = nullptr;
    cudaError_t e = cudaEventCreate(&start);
    if (e == cudaSuccess) e = cudaEventCreate(&stop);
    ms.clear();
    for (int rep = 0; rep < reps && e == cudaSuccess; ++rep) {
        e = cudaEventRecord(start);
        launch();
        if (e == cudaSuccess) e = cudaGetLastError();
        if (e == cudaSuccess) e = cudaEventRecord(stop);
        if (e == cudaSuccess) e = cudaEventSynchronize(stop);
        float t = 0;
        if (e == cudaSuccess) e = cudaEventElapsedTime(&t, start, stop);
        ms.push_back(t);
    }
    if (start) cudaEventDestroy(start);
    if (stop) cudaEventDestroy(stop);
    std::sort(ms.begin(), ms.end());
    return e;
}

/// size x size primary rays of a pinhole camera at `eye` looking at the origin, y up, with a
/// vertical half field of view of `half_fov_deg` degrees; row-major from the top-left pixel.
inline std::vector<core::Ray> pinhole_rays(core::Vec3 eye, int size, float half_fov_deg) {
    const core::Vec3 f = core::normalize(core::Vec3{0, 0, 0} - eye);
    const core::Vec3 right = core::normalize(core::cross(f, core::Vec3{0, 1, 0}));
    const core::Vec3 up = core::cross(right, f);
    const float tan_half = std::tan(half_fov_deg * core::k_pi / 180.0f);
    std::vector<core::Ray> rays;
    rays.reserve(std::size_t(size) * size);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const float sx = ((x + 0.5f) / size * 2 - 1) * tan_half,
                        sy = (1 - (y + 0.5f) / size * 2) * tan_half;
            rays.push_back({eye, core::normalize(f + right * sx + up * sy), core::k_inf, 0u});
        }
    return rays;
}

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
