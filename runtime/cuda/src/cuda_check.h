// PointRT CUDA backend: every CUDA call is checked (DESIGN.md, GPU work). Host-only header.
#pragma once

#include <cuda_runtime.h>

#include <string>

#include "prt/error.h"

namespace prt::cuda {

/// Throws prt::Error "FILE:LINE: EXPR: CUDA error NAME: DESCRIPTION".
[[noreturn]] inline void throw_cuda_error(cudaError_t e, const char* expr, const char* file, int line) {
    throw Error(std::string(file) + ":" + std::to_string(line) + ": " + expr + ": CUDA error " +
                cudaGetErrorName(e) + ": " + cudaGetErrorString(e));
}

}  // namespace prt::cuda

/// Checks a CUDA runtime call; throws prt::Error with file, line and the CUDA error string.
#define PRT_CUDA_CHECK(expr)                                                            \
    do {                                                                                \
        const cudaError_t prt_cuda_status_ = (expr);                                    \
        if (prt_cuda_status_ != cudaSuccess)                                            \
            ::prt::cuda::throw_cuda_error(prt_cuda_status_, #expr, __FILE__, __LINE__); \
    } while (0)

/// Checks the last kernel launch (configuration errors) without synchronizing.
#define PRT_CUDA_CHECK_LAUNCH() PRT_CUDA_CHECK(cudaGetLastError())
