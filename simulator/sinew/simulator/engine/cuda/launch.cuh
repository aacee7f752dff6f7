#pragma once
// Launch helpers and block-level reductions of the CUDA engine's kernels (only kernel entry points
// read threadIdx; these take it as an argument), and forall: the generic kernel that runs a
// one-item loop body of passes/ (the CPU runs the same body with cpu_for_each).
#include <cuda_runtime.h>

#include <cstddef>
#include <cstdint>

#include "sinew/simulator/engine/cuda/cuda_check.cuh"

namespace sinew::simulator::cuda {

constexpr int kBlock = 256;

// Sum of `value` over the kBlock threads of a block: a tree reduction in the shared array `s`
// (kBlock doubles) in a fixed order, so the sum is the same bits every run. Valid in every thread
// after the call; `tid` is the caller's threadIdx.x (only kernel entry points read it).
__device__ __forceinline__ double block_sum(double value, double* s, int tid) {
  s[tid] = value;
  __syncthreads();
  for (int stride = kBlock / 2; stride > 0; stride /= 2) {
    if (tid < stride) s[tid] += s[tid + stride];
    __syncthreads();
  }
  const double sum = s[0];
  __syncthreads();  // `s` may be reused at once
  return sum;
}

// Whether this block is the last of its grid to get here (CUDA's threadFenceReduction pattern):
// every block's thread 0 wrote its partial before the call; the last block may then read all
// partials (with __ldcg: past the L1) and sum them in index order (deterministic). The counter is
// back at 0 afterwards.
__device__ __forceinline__ bool last_block(unsigned* counter, int tid, unsigned blocks) {
  __shared__ bool last;
  __threadfence();
  if (tid == 0) {
    const unsigned done = atomicAdd(counter, 1u);
    last = done == blocks - 1;
    if (last) *counter = 0;
  }
  __syncthreads();
  return last;
}

// Σ partial[0 .. count) in the fixed order of blowup/work totals (strided per thread, then
// block_sum); for the last block only.
__device__ __forceinline__ double sum_partials(const double* partial, int count, double* s,
                                               int tid) {
  double w = 0;
  for (int k = tid; k < count; k += kBlock) w += __ldcg(partial + k);
  return block_sum(w, s, tid);
}

template <typename... P, typename... A>
void launch_kernel(void (*kernel)(P...), unsigned grid, unsigned block, std::size_t shared,
                   cudaStream_t s, bool programmatic, A... args) {
  cudaLaunchAttribute attribute[1] = {};
  attribute[0].id = cudaLaunchAttributeProgrammaticStreamSerialization;
  attribute[0].val.programmaticStreamSerializationAllowed = 1;
  cudaLaunchConfig_t config = {};
  config.gridDim = dim3(grid);
  config.blockDim = dim3(block);
  config.dynamicSmemBytes = shared;
  config.stream = s;
  config.attrs = attribute;
  config.numAttrs = programmatic ? 1 : 0;
  SINEW_CUDA_CHECK(cudaLaunchKernelEx(&config, kernel, P(args)...));
}
inline unsigned blocks_for(std::size_t n) {
  return unsigned((n + kBlock - 1) / kBlock);
}

// Programmatic dependent launch (Hopper, sm_90; docs/cuda-backend.md, "Launches"). The step's
// kernels in a graph are launched with programmatic stream serialisation: a kernel's blocks may
// start while the kernel before it in the stream still runs. Each such kernel first loads only
// what no kernel of the step writes (tables, static data, and what the kernel two launches back
// wrote: see below), then calls wait_for_previous_kernel(), which returns once the kernel before
// it has completed with its writes visible, and only then reads its inputs and writes anything.
// It calls let_next_kernel_start() right after the wait, so the next kernel's blocks can take the
// SM room this grid leaves (and run their own loads) as soon as all of this grid's blocks are
// past their wait: a kernel two launches back has therefore always completed when a kernel's
// first loads run. Both are no-ops for a kernel launched plainly (or below sm_90).
__device__ __forceinline__ void wait_for_previous_kernel() {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
  asm volatile("griddepcontrol.wait;" ::: "memory");
#endif
}
__device__ __forceinline__ void let_next_kernel_start() {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
  asm volatile("griddepcontrol.launch_dependents;" ::: "memory");
#endif
}

// The generic kernel: body(i) for i < n, one thread each (passes/cpu_for_each.hpp's cpu_for_each
// on the CPU).
template <typename Body>
__global__ void __launch_bounds__(kBlock) forall_kernel(std::int32_t n, Body body) {
  const std::int32_t i = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  if (i < n) body(i);
}

template <typename Body>
void forall(std::size_t n, cudaStream_t s, const Body& body) {
  if (n == 0) return;
  forall_kernel<<<blocks_for(n), kBlock, 0, s>>>(std::int32_t(n), body);
  SINEW_CUDA_LAUNCHED();
}

}  // namespace sinew::simulator::cuda
