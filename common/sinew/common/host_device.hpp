#pragma once
// SINEW_HD marks a function callable from host code and from CUDA kernels. Physics laws are
// written once as SINEW_HD functions and called by both backends (docs/physics.md).
#if defined(__CUDACC__)
#define SINEW_HD __host__ __device__
#define SINEW_HD_INLINE __host__ __device__ __forceinline__
#else
#define SINEW_HD
#define SINEW_HD_INLINE inline
#endif
