#pragma once
// The element kernel (gather and atomic assembly, and per-element energies): one thread per
// element of a collection running the element pass's loop body (passes/element_pass.hpp), its
// loads before the wait of a programmatic launch (cuda/launch.cuh).
#include <cuda_runtime.h>

#include <cstddef>
#include <cstdint>

#include "sinew/simulator/engine/cuda/launch.cuh"
#include "sinew/simulator/passes/element_pass.hpp"
#include "sinew/simulator/passes/step_status.hpp"

namespace sinew::simulator::cuda {

// kMode: 0 gather (E × 8 buffer), 1 atomic (into nodal forces), 2 gather + per-element energies.
template <typename T, bool kElastic, bool kMuscle, bool kHourglass, int kMode>
__global__ void __launch_bounds__(kBlock)
    element_kernel(ElementData<T> d, const std::int32_t* __restrict__ list, std::int32_t count,
                   const Vec3<T>* __restrict__ u, const T* __restrict__ activation,
                   Vec3<T>* __restrict__ out, double* __restrict__ energy, StepStatus* status) {
  const std::int32_t i = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  if (i >= count) return;
  const std::int32_t e = list[i];
  const ElementStart<T> start = element_start<T, kMuscle>(d, e, activation);
  wait_for_previous_kernel();
  let_next_kernel_start();
  Vec3<T> fe[8];
  double strain = 0, elastic = 0, hourglass = 0;
  const T j = element_finish<T, kElastic, kMuscle, kHourglass, kMode == 2>(d, start, u, fe, strain,
                                                                           elastic, hourglass);
  if (!(j > T(0))) status->bad_jacobian = 1;
  if constexpr (kMode == 1) {
#pragma unroll
    for (int a = 0; a < 8; ++a) {
      atomicAdd(&out[start.ids[a]].x, fe[a].x);
      atomicAdd(&out[start.ids[a]].y, fe[a].y);
      atomicAdd(&out[start.ids[a]].z, fe[a].z);
    }
  } else {
    // Corner-major (a · E + e): consecutive elements write consecutive entries, and the nodes of a
    // lattice row read consecutive entries back in the gather.
#pragma unroll
    for (int a = 0; a < 8; ++a)
      out[std::size_t(a) * std::size_t(d.elements) + std::size_t(e)] = fe[a];
  }
  if constexpr (kMode == 2) {
    energy[3 * std::size_t(e)] = strain;
    energy[3 * std::size_t(e) + 1] = elastic;
    energy[3 * std::size_t(e) + 2] = hourglass;
  }
}

}  // namespace sinew::simulator::cuda
