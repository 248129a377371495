// PointRT core: the one macro that makes a function callable from host and device code.
// Everything under prt/core/ compiles with g++ (host only) and with nvcc (host + device): plain
// functions over POD structs and non-owning views, no STL containers, exceptions, virtual calls,
// allocation or recursion (DESIGN.md, "The shared core").
#pragma once

#if defined(__CUDACC__)
/// Marks a function as callable from host and device code (empty for host-only compilers).
#define PRT_HD __host__ __device__
/// Forces inlining on both compilers (hot inner loops of traversal and intersection).
#define PRT_INLINE __forceinline__
#else
#define PRT_HD
#define PRT_INLINE inline __attribute__((always_inline))
#endif

#if defined(__CUDACC__)
/// Keeps a rarely taken, register-hungry path out of its caller's register allocation on the
/// device (a call instead of inlining); the host compiler decides for itself.
#define PRT_NOINLINE __noinline__
#else
#define PRT_NOINLINE
#endif

#if defined(__CUDACC__)
/// Unrolls the following short fixed-count loop (per-axis loops) in device code.
#define PRT_UNROLL _Pragma("unroll")
#else
#define PRT_UNROLL
#endif

#if defined(__CUDA_ARCH__)
/// True while compiling device code (nvcc's device pass).
#define PRT_DEVICE_CODE 1
#else
#define PRT_DEVICE_CODE 0
#endif

#ifndef PRT_BATCHED_WALK
/// 0: one leaf per pass of the intersection loop ("if-if"); 1: a ray walks on until the next leaf
/// whose splats must be read before reading any ("while-while", splat.h next_leaf). The same hits
/// either way; only how the threads of a GPU warp line up changes. Measured on an H100 (prt-bench,
/// 1M-point room, runtime/README.md): 1 is 49% slower for primary rays and no faster for 4-bounce
/// reflections, so 0 is the default; 1 stays selectable for other scenes (CMake: -DPRT_BATCHED_WALK=ON).
#define PRT_BATCHED_WALK 0
#endif

#ifndef PRT_COUNT_WORK
/// 1: count octree leaves visited and splats tested per ray (WalkStats, benchmark diagnostics);
/// 0: leave those two counters at zero (the counters cost registers in GPU kernels).
#define PRT_COUNT_WORK 1
#endif
#if PRT_COUNT_WORK
#define PRT_COUNT(counter) (++(counter))
#else
#define PRT_COUNT(counter) ((void)0)
#endif
