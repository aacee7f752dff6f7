#pragma once
// The constraint kernel (models with sliding: one thread per constrained node running its
// constraint program after the node kernel) and the sliding list refresh kernel (ahead of a step,
// beside its element and node kernels): passes/constraint_program.hpp, passes/sliding_lists.hpp.
#include <cuda_runtime.h>

#include <cstdint>

#include "sinew/simulator/engine/cuda/launch.cuh"
#include "sinew/simulator/engine/cuda/node_kernels.cuh"
#include "sinew/simulator/passes/constraint_program.hpp"

namespace sinew::simulator::cuda {

// Models with sliding: after the node kernel, one thread per constrained node runs its program
// and adds to the node's accumulated work the program's work and the change its constraints make
// to the gravity term (the node kernel added g · (u(n+1) − u(n−1))/2 before constraints).
// lists_ready: no list refresh was forked for this step (the lists may be read before the wait).
template <typename T, int kSlide>
__global__ void __launch_bounds__(kBlock, kSlide == 2 ? 4 : 1)
    constraint_kernel(ConstraintData<T> d, const T* factor, bool loads, Vec3<T>* un,
                      const Vec3<T>* up, StepSums sums, bool lists_ready) {
  const std::int32_t c = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  if (c >= d.count) return;
  const std::int32_t i = d.node[c], begin = d.offset[c], end = d.offset[c + 1];
  // A sliding node's warm start is loaded before the wait (its first op is the slide when it has
  // no nodal force or captured prescription).
  SlideStart<T> start{};
  std::int32_t started = -1;
  if constexpr (kSlide != 0) {
    const std::int32_t code = d.op[begin];
    if ((code >> kOpShift) == kOpSlide) {
      started = code & kOpArg;
      start = slide_start(d.slide, started, kSlide == 2 && lists_ready);
    }
  }
  wait_for_previous_kernel();
  let_next_kernel_start();
  const Vec3<T> before = un[i];
  double w = 0;
  const bool work = loads && sums.work_acc;
  const Vec3<T> v =
      run_program<T, kSlide>(d, i, begin, end, factor, loads, before, up, work, w, start, started);
  un[i] = v;
  if (work) {
    if (d.gravity)
      for (int k = 0; k < 3; ++k)
        w += double(d.gravity[i][k]) * 0.5 * (double(v[k]) - double(before[k]));
    sums.work_acc[i] += w;
  }
}

// Ahead of a step, concurrently with its element and node kernels (a parallel branch of the
// graph): one thread per sliding entry k refreshes its list at its position of u(n), keeping the
// anchor while within s/2 of it, so the grid walks leave the step's critical path and
// constraint_kernel<T, 2> carries no search code. A node that then moves more than s/2 in the step
// raises slide_miss there (exactness is kept by a replay).
template <typename T>
__global__ void __launch_bounds__(kBlock)
    slide_refresh_kernel(SlideData<T> d, const Vec3<T>* __restrict__ rest, const Vec3<T>* u) {
  const std::int32_t k = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  if (k >= d.count) return;
  const std::int32_t i = d.node[k];
  refresh_slide_list(d, k, rest[i] + u[i], T(0.5));
}

}  // namespace sinew::simulator::cuda
