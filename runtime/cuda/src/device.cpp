// PointRT CUDA: device queries (prt/cuda/device.h). Host code over the CUDA runtime.
#include "prt/cuda/device.h"

#include <cuda_runtime.h>

namespace prt::cuda {

namespace {

std::string error_line(cudaError_t e) {
    return std::string(cudaGetErrorName(e)) + ": " + cudaGetErrorString(e);
}

}  // namespace

bool device_available(std::string* why) {
    int count = 0;
    const cudaError_t e = cudaGetDeviceCount(&count);
    if (e != cudaSuccess) {
        if (why) {
            *why = e == cudaErrorInsufficientDriver
                       ? "no usable CUDA device: no NVIDIA driver, or one too old for this build ("
                   : e == cudaErrorNoDevice ? "no CUDA device found ("
                                            : "no usable CUDA device (";
            *why += error_line(e) + ")";
        }
        cudaGetLastError();  // clear the sticky-free error so later calls start clean
        return false;
    }
    if (count == 0) {
        if (why) *why = "no CUDA device found";
        return false;
    }
    return true;
}

std::string device_name() {
    if (!device_available()) return {};
    cudaDeviceProp prop{};
    if (cudaGetDeviceProperties(&prop, 0) != cudaSuccess) return {};
    return prop.name;
}

void warm_up_device() {
    if (cudaSetDevice(0) != cudaSuccess || cudaFree(nullptr) != cudaSuccess) cudaGetLastError();
}

void release_device() {
    if (cudaDeviceReset() != cudaSuccess) cudaGetLastError();
}

}  // namespace prt::cuda
