// PointRT CUDA backend: every CUDA call is checked (DESIGN.md, GPU work), and every kernel starts
// through launch_kernel (grid size, launch, check). Host-only header.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>
#include <source_location>
#include <string>
#include <utility>

#include "prt/error.h"

namespace prt::cuda {

/// Throws prt::Error "FILE:LINE: EXPR: CUDA error NAME: DESCRIPTION".
[[noreturn]] inline void throw_cuda_error(cudaError_t e, const char* expr, const char* file, int line) {
    throw Error(std::string(file) + ":" + std::to_string(line) + ": " + expr + ": CUDA error " +
                cudaGetErrorName(e) + ": " + cudaGetErrorString(e));
}

/// The shape of a kernel launch: blocks, threads per block, stream, and the caller's place (the file
/// and line an error names).
struct LaunchShape {
    dim3 blocks;
    dim3 threads;
    cudaStream_t stream = nullptr;
    std::source_location where;
};

/// `count` threads in 1-D blocks of `block` (ceil(count / block) blocks; throws prt::Error beyond
/// CUDA's 2^31 - 1 blocks).
inline LaunchShape launch_1d(std::uint64_t count, unsigned block, cudaStream_t stream = nullptr,
                             std::source_location where = std::source_location::current()) {
    const std::uint64_t blocks = (count + block - 1) / block;
    if (blocks > 0x7fffffffu)
        throw Error(std::string(where.file_name()) + ":" + std::to_string(where.line()) + ": " +
                    std::to_string(count) + " threads exceed a kernel grid");
    return {dim3(static_cast<unsigned>(blocks)), dim3(block), stream, where};
}

/// A launch of the given blocks (1-D or 2-D) of `block` threads.
inline LaunchShape launch_grid(dim3 blocks, unsigned block, cudaStream_t stream = nullptr,
                               std::source_location where = std::source_location::current()) {
    return {blocks, dim3(block), stream, where};
}

#ifdef __CUDACC__
/// Launches kernel<<<blocks, threads, 0, stream>>>(args...) and checks the launch (configuration
/// errors, without synchronizing): prt::Error "FILE:LINE: kernel launch: CUDA error NAME: ..." at
/// the caller's place.
template <class... Params, class... Args>
void launch_kernel(const LaunchShape& shape, void (*kernel)(Params...), Args&&... args) {
    kernel<<<shape.blocks, shape.threads, 0, shape.stream>>>(std::forward<Args>(args)...);
    const cudaError_t status = cudaGetLastError();
    if (status != cudaSuccess)
        throw_cuda_error(status, "kernel launch", shape.where.file_name(),
                         static_cast<int>(shape.where.line()));
}
#endif  // __CUDACC__ (host .cpp files of the backend use the checks above, not the launch)

}  // namespace prt::cuda

/// Checks a CUDA runtime call; throws prt::Error with file, line and the CUDA error string.
#define PRT_CUDA_CHECK(expr)                                                            \
    do {                                                                                \
        const cudaError_t prt_cuda_status_ = (expr);                                    \
        if (prt_cuda_status_ != cudaSuccess)                                            \
            ::prt::cuda::throw_cuda_error(prt_cuda_status_, #expr, __FILE__, __LINE__); \
    } while (0)

/// Checks the last kernel launch (configuration errors) without synchronizing (launch_kernel does
/// this itself).
#define PRT_CUDA_CHECK_LAUNCH() PRT_CUDA_CHECK(cudaGetLastError())
