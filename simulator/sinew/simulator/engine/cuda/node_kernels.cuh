#pragma once
// The node kernel (gather and atomic assembly): one thread per node running the node pass's loop
// body (passes/node_pass.hpp) and, for models without sliding, its loads and constraints
// (passes/constraint_program.hpp); and the device side of the blow-up test. The tile kernel
// (cuda/tile_kernel.cuh) finishes its nodes with the same functions.
#include <cuda_runtime.h>

#include <cstdint>

#include "sinew/simulator/engine/cuda/launch.cuh"
#include "sinew/simulator/passes/constraint_program.hpp"
#include "sinew/simulator/passes/node_pass.hpp"
#include "sinew/simulator/passes/step_status.hpp"

namespace sinew::simulator::cuda {

// External work and the blow-up test. The work is accumulated per node in double (each node adds
// its own terms, in step order: no reduction per step); it is summed, in a fixed order, only where
// it is read: at blow-up test steps (node kernel, below) and at sync points (host).
struct StepSums {
  double* work_acc;         // N per-node accumulated work (J), or null: no work in this model
  const double* work_base;  // work carried in by restore() (J)
  double* work_partial;     // per node-kernel block: Σ work_acc (test steps)
  double* kinetic_partial;  // per node-kernel block: ½ M |v|² (test steps)
  unsigned* counter;        // last-block detection of the node kernel
  const BlowupBound* bound;
  double inv_dt;
};

// A node's step in two parts. move_node: the central-difference update of node i from its internal
// force f (ui, upi: its u(n), u(n−1); im: its inverse mass, loaded by the caller) and the finite
// check; with energy_test it adds its kinetic energy at u(n) to ke. Returns u(n+1) before its loads
// and constraints.
template <typename T, bool kGravity>
__device__ __forceinline__ Vec3<T> move_node(const NodeData<T>& d, std::int32_t i, const Vec3<T>& f,
                                             const Vec3<T>& ui, const Vec3<T>& upi, T im,
                                             StepStatus* status, const StepSums& sums,
                                             bool energy_test, double& ke) {
  const Vec3<T> v = advance_node<T, kGravity>(d, i, f, ui, upi, im);
  if (!all_finite(v)) status->bad_displacement = 1;
  if (energy_test) ke += node_kinetic_energy(ui, upi, im, sums.inv_dt);
  return v;
}

// finish_node: (kProgram) node i's loads and constraints, its ops [begin, end) of program.op, on
// its u(n+1) v; writes u(n+1) to un, and adds the node's work of this step to its accumulator
// (gravity; kProgram: its loads and constraint forces; without kProgram gravity before constraints,
// the constraint kernel adds the rest). With energy_test it adds to w_old the node's work up to
// step n − 1 (the accumulator before this step). kSlide: as run_program.
template <typename T, bool kGravity, bool kProgram, int kSlide>
__device__ __forceinline__ void finish_node(const NodeData<T>& d, std::int32_t i, Vec3<T> v,
                                            const Vec3<T>& upi, const Vec3<T>* __restrict__ up,
                                            Vec3<T>* __restrict__ un, const StepSums& sums,
                                            const ConstraintData<T>& program, std::int32_t begin,
                                            std::int32_t end, const T* factor, bool energy_test,
                                            double& w_old) {
  double w = 0;
  bool has_work = kGravity;
  if constexpr (kProgram) {
    v = run_program<T, kSlide>(program, i, begin, end, factor, true, v, up, sums.work_acc, w);
    has_work = has_work || begin < end;
  }
  un[i] = v;
  if constexpr (kGravity) {
    const Vec3<T> g = d.gravity[i];
    for (int c = 0; c < 3; ++c) w += double(g[c]) * 0.5 * (double(v[c]) - double(upi[c]));
  }
  if (sums.work_acc && (has_work || energy_test)) {
    const double w0 = sums.work_acc[i];
    if (has_work) sums.work_acc[i] = w0 + w;
    w_old += w0;
  }
}

// The blow-up test at the end of a node pass, for every thread of the block: the block's sums of
// ke and w_old, then, by the last block of the grid in block order, the kinetic energy of u(n)
// against the bound with the work up to step n − 1.
__device__ __forceinline__ void blowup_test(double ke, double w_old, const StepSums& sums,
                                            StepStatus* status, int tid, unsigned block,
                                            unsigned blocks) {
  __shared__ double sh[kBlock];
  const double k_sum = block_sum(ke, sh, tid);
  const double w_sum = sums.work_acc ? block_sum(w_old, sh, tid) : 0.0;  // uniform
  if (tid == 0) {
    sums.kinetic_partial[block] = k_sum;
    sums.work_partial[block] = w_sum;
  }
  if (last_block(sums.counter, tid, blocks)) {
    const double kinetic = sum_partials(sums.kinetic_partial, int(blocks), sh, tid);
    const double work = *sums.work_base + sum_partials(sums.work_partial, int(blocks), sh, tid);
    if (tid == 0 &&
        (!isfinite(kinetic) || kinetic > sums.bound->factor * (sums.bound->base + fabs(work))))
      status->blowup = 1;
  }
}

// Gather (or read and clear the atomic sums), then move_node and finish_node. kEnergyTest: the
// blow-up test where the step's row flags it (*energy_flag ≠ 0; the same value for every block).
template <typename T, bool kGather, bool kGravity, bool kEnergyTest, bool kProgram>
__global__ void __launch_bounds__(kBlock)
    node_kernel(NodeData<T> d, const Vec3<T>* __restrict__ element_force,
                Vec3<T>* __restrict__ f_sum, const Vec3<T>* __restrict__ u,
                const Vec3<T>* __restrict__ up, Vec3<T>* __restrict__ un, StepStatus* status,
                StepSums sums, ConstraintData<T> program, const std::int32_t* node_offset,
                const T* factor, const T* energy_flag) {
  const std::int32_t i = std::int32_t(blockIdx.x * blockDim.x + threadIdx.x);
  bool energy_test = false;
  if constexpr (kEnergyTest) energy_test = *energy_flag != T(0);
  double ke = 0, w_old = 0;
  // Before the wait: offsets, inverse mass, u(n) and u(n−1) (written two launches back, by the
  // previous steps' node or constraint kernels). Bringing the program's data into L1 here as well
  // cost the skin block 0.0149 → 0.0161 ms per step (docs/performance.md).
  std::int32_t first = 0, last = 0, begin = 0, end = 0;  // its incidence entries, its ops
  T im = T(0);
  Vec3<T> ui{T(0), T(0), T(0)}, upi = ui;
  if (i < d.n) {
    if constexpr (kGather) {
      first = d.offset[i];
      last = d.offset[i + 1];
    }
    if constexpr (kProgram) {
      begin = node_offset[i];
      end = node_offset[i + 1];
    }
    im = d.inverse_mass[i];
    ui = u[i];
    upi = up[i];
  }
  wait_for_previous_kernel();
  let_next_kernel_start();
  if (i < d.n) {
    Vec3<T> f;
    if constexpr (kGather) {
      f = physics::gather_node_force(element_force, d.inc, first, last);
    } else {
      f = f_sum[i];
      f_sum[i] = Vec3<T>{T(0), T(0), T(0)};
    }
    const Vec3<T> v = move_node<T, kGravity>(d, i, f, ui, upi, im, status, sums, energy_test, ke);
    finish_node<T, kGravity, kProgram, 0>(d, i, v, upi, up, un, sums, program, begin, end, factor,
                                          energy_test, w_old);
  }
  if (energy_test) blowup_test(ke, w_old, sums, status, int(threadIdx.x), blockIdx.x, gridDim.x);
}

}  // namespace sinew::simulator::cuda
