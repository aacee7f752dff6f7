#pragma once
// The tile kernel of tiled assembly (lattice_tiles.hpp, docs/cuda-backend.md "Tiled assembly").
#include <cuda_pipeline.h>
#include <cuda_runtime.h>

#include <cstddef>
#include <cstdint>

#include "sinew/simulator/engine/cuda/launch.cuh"
#include "sinew/simulator/engine/cuda/node_kernels.cuh"
#include "sinew/simulator/engine/lattice_tiles.hpp"
#include "sinew/simulator/passes/element_pass.hpp"

namespace sinew::simulator::cuda {

// Tiled assembly (lattice_tiles.hpp): one block per tile walks its node layers upwards; per layer
// it computes the element slots of the layer (one thread per slot, physics::element_forces) from
// the u windows of the node layers below and above them, keeps their corner forces in shared
// memory and lets each of its nodes sum its entries in the gather order (lattice_tiles.hpp), then
// move_node and finish_node; nodes with loads or constraints (kProgram) finish after the last
// layer. Same sums in the same order as gather, with no element force buffer in DRAM.
// Software-pipelined: the table entries, u window and node data a layer needs are loaded one
// layer ahead, so their latency overlaps the element work (three window buffers in rotation; the
// u windows copied to shared memory asynchronously, without registers).
struct TileData {
  const std::int32_t* layers;  // per tile
  const std::int32_t* window;  // tiles × window_stride node ids
  const std::int32_t* slot;    // tiles × slot_stride element ids
  std::int64_t window_stride, slot_stride;
};
constexpr int kTileWindowPoints = kTileWindow * kTileWindow;
constexpr int kTileSlotCount = kTileSlots * kTileSlots;
static_assert(kTileSlotCount == kBlock, "one thread per element slot");
static_assert(kTileWindowPoints <= 2 * kBlock, "two window points per thread at most");
// Shared memory of tile_kernel: three u windows, the top corners of two element layers (the one
// below the node layer and the one being computed), the bottom corners of one.
template <typename T>
constexpr std::size_t tile_shared_bytes() {
  return sizeof(Vec3<T>) * std::size_t(3 * kTileWindowPoints + 12 * kTileSlotCount);
}
// Blocks of tile_kernel resident per SM the compiler must allow (registers ≤ 80 in float): three
// hide the element work's latency better than two with more registers (docs/performance.md:
// 0.0639 → 0.0574 ms/step on the face-scale model, no spills). Double keeps the compiler's choice.
template <typename T>
constexpr int kTileMinBlocks = sizeof(T) == 4 ? 3 : 1;

// dst (shared) = u[id] (global) without passing through registers (Hopper/Ampere cp.async; waited
// for with __pipeline_wait_prior), or zero where id < 0.
template <typename T>
__device__ __forceinline__ void copy_point_async(Vec3<T>* dst, const Vec3<T>* u, std::int32_t id) {
  if (id < 0) {
    *dst = Vec3<T>{T(0), T(0), T(0)};
    return;
  }
  const T* src = &u[id].x;
  T* d = &dst->x;
  for (int c = 0; c < 3; ++c) __pipeline_memcpy_async(d + c, src + c, sizeof(T));
}

template <typename T, bool kElastic, bool kMuscle, bool kHourglass, bool kGravity, bool kProgram>
__global__ void __launch_bounds__(kBlock, kTileMinBlocks<T>)
    tile_kernel(TileData tiles, ElementData<T> ed, NodeData<T> nd, const Vec3<T>* __restrict__ u,
                const T* __restrict__ activation, const Vec3<T>* __restrict__ up,
                Vec3<T>* __restrict__ un, StepStatus* status, StepSums sums,
                ConstraintData<T> program, const std::int32_t* node_offset, const T* factor,
                const T* energy_flag) {
  // The blow-up test where the step's row flags it (null: none in this launch).
  const bool energy_test = energy_flag != nullptr && *energy_flag != T(0);
  extern __shared__ __align__(16) unsigned char tile_shared[];
  Vec3<T>* const window = reinterpret_cast<Vec3<T>*>(tile_shared);  // [3][window points]
  Vec3<T>* const top = window + 3 * kTileWindowPoints;              // [2][4 corners][slots]
  Vec3<T>* const bottom = top + 8 * kTileSlotCount;                 // [4 corners][slots]
  const int tid = int(threadIdx.x);
  const std::int32_t* wtab = tiles.window + std::int64_t(blockIdx.x) * tiles.window_stride;
  const std::int32_t* stab = tiles.slot + std::int64_t(blockIdx.x) * tiles.slot_stride;
  const int layers = tiles.layers[blockIdx.x];  // window layers 0 .. layers + 1
  const Vec3<T> zero{T(0), T(0), T(0)};
  // This thread's window points (tid, and tid + kBlock when that is < kTileWindowPoints), its
  // element slot (sx, sy) and, for tid < 225, its node at window point (wx, wy).
  const bool second = tid + kBlock < kTileWindowPoints;
  const int sx = tid % kTileSlots, sy = tid / kTileSlots;
  const bool owner = tid < kTileNodes * kTileNodes;
  const int wx = 1 + tid % kTileNodes, wy = 1 + tid / kTileNodes;
  const int node_point = wy * kTileWindow + wx;
  auto window_ids = [&](int l, std::int32_t& a, std::int32_t& b) {
    a = l <= layers + 1 ? wtab[l * kTileWindowPoints + tid] : -1;
    b = second && l <= layers + 1 ? wtab[l * kTileWindowPoints + tid + kBlock] : -1;
  };
  auto fetch = [&](std::int32_t id) { return id >= 0 ? u[id] : zero; };
  // Prologue: windows 0 and 1 in buffers 0 and 1; the ids of window 2; element layer 0; the node
  // of window layer 1. The tables are read before the wait for the previous kernel.
  std::int32_t ia, ib, window_id[2][2];
  for (int l = 0; l < 2; ++l) window_ids(l, window_id[l][0], window_id[l][1]);
  window_ids(2, ia, ib);
  std::int32_t e = stab[tid];
  std::int32_t row_index = e >= 0 ? ed.row[e] : 0;
  wait_for_previous_kernel();
  let_next_kernel_start();
  for (int l = 0; l < 2; ++l) {
    window[l * kTileWindowPoints + tid] = fetch(window_id[l][0]);
    if (second) window[l * kTileWindowPoints + tid + kBlock] = fetch(window_id[l][1]);
  }
  std::int32_t node = -1;  // window layer 0 has no node of the tile
  Vec3<T> node_up = zero;
  T node_im = T(0);
  std::int32_t node_begin = 0, node_end = 0;  // its ops (kProgram)
  __syncthreads();
  double ke = 0, w_old = 0;
  for (int l = 0; l <= layers; ++l) {
    // A: loads for later layers, issued before the element work: window l + 2 (ids known), the
    // ids of window l + 3, the element of layer l + 1 and the node of window layer l + 1.
    {  // window l + 2 into the buffer window l − 1 had (last read before the previous barrier)
      Vec3<T>* w2 = window + ((l + 2) % 3) * kTileWindowPoints;
      copy_point_async(w2 + tid, u, ia);
      if (second) copy_point_async(w2 + tid + kBlock, u, ib);
      __pipeline_commit();
    }
    window_ids(l + 3, ia, ib);
    const std::int32_t e_next = l + 1 <= layers ? stab[(l + 1) * kTileSlotCount + tid] : -1;
    const std::int32_t node_next =
        owner && l + 1 <= layers ? wtab[(l + 1) * kTileWindowPoints + node_point] : -1;
    // B: element layer l (between window layers l and l + 1).
    const Vec3<T>* wl = window + (l % 3) * kTileWindowPoints;
    const Vec3<T>* wu = window + ((l + 1) % 3) * kTileWindowPoints;
    Vec3<T>* top_l = top + (l & 1) * 4 * kTileSlotCount;
    if (e >= 0) {
      const int p = sy * kTileWindow + sx;
      const Vec3<T> ue[8] = {wl[p], wl[p + 1], wl[p + kTileWindow + 1], wl[p + kTileWindow],
                             wu[p], wu[p + 1], wu[p + kTileWindow + 1], wu[p + kTileWindow]};
      const physics::ElementRow<T> row = ed.rows[row_index];
      physics::MuscleEntries<T> m{
          ed.muscle_id, ed.muscle_fraction, ed.muscle_fibre, ed.muscle_params, activation, 0, 0};
      if constexpr (kMuscle) {
        m.begin = ed.muscle_offset[e];
        m.end = ed.muscle_offset[e + 1];
      }
      Vec3<T> fe[8];
      const auto r =
          physics::element_forces<T, kElastic, kMuscle, kHourglass, false>(ue, ed.h, row, m, fe);
      if (!(r.j > T(0))) status->bad_jacobian = 1;
#pragma unroll
      for (int c = 0; c < 4; ++c) {
        bottom[c * kTileSlotCount + tid] = fe[c];
        top_l[c * kTileSlotCount + tid] = fe[4 + c];
      }
    } else {
#pragma unroll
      for (int c = 0; c < 4; ++c) {
        bottom[c * kTileSlotCount + tid] = zero;
        top_l[c * kTileSlotCount + tid] = zero;
      }
    }
    __syncthreads();
    // D: the node of window layer l (node layer l − 1 of the tile).
    if (l >= 1 && node >= 0) {
      const Vec3<T>* below = top + ((l - 1) & 1) * 4 * kTileSlotCount;
      Vec3<T> f = zero;
#pragma unroll
      for (int q = 0; q < 4; ++q)
        f += below[tile_gather_corner(q) * kTileSlotCount + tile_gather_slot(wx, wy, q)];
#pragma unroll
      for (int q = 0; q < 4; ++q)
        f += bottom[tile_gather_corner(q) * kTileSlotCount + tile_gather_slot(wx, wy, q)];
      // Nodes with loads or constraints finish after the layers (their program's dependent loads
      // then overlap instead of holding the block at each layer's barrier).
      const Vec3<T> v = move_node<T, kGravity>(nd, node, f, wl[node_point], node_up, node_im,
                                               status, sums, energy_test, ke);
      if (node_begin == node_end)
        finish_node<T, kGravity, false, 0>(nd, node, v, node_up, up, un, sums, program, 0, 0,
                                           factor, energy_test, w_old);
      else
        un[node] = v;
    }
    // Next layer's element row and node data (their ids had the element work to arrive; the node
    // data has the next element work to arrive).
    e = e_next;
    row_index = e >= 0 ? ed.row[e] : 0;
    node = node_next;
    if (node >= 0) {
      node_up = up[node];
      node_im = nd.inverse_mass[node];
      if constexpr (kProgram) {
        node_begin = node_offset[node];
        node_end = node_offset[node + 1];
      }
    }
    __pipeline_wait_prior(0);  // window l + 2 has landed (the next layer reads it)
    __syncthreads();  // the next layer overwrites `bottom`, the top corners read here, window l
  }
  if constexpr (kProgram) {  // the deferred nodes: their u(n+1) before the program is in un
    if (owner)
      for (int l = 1; l <= layers; ++l) {
        const std::int32_t i = wtab[l * kTileWindowPoints + node_point];
        if (i < 0) continue;
        const std::int32_t begin = node_offset[i], end = node_offset[i + 1];
        if (begin == end) continue;
        finish_node<T, kGravity, true, 0>(nd, i, un[i], up[i], up, un, sums, program, begin, end,
                                          factor, energy_test, w_old);
      }
  }
  if (energy_test) blowup_test(ke, w_old, sums, status, tid, blockIdx.x, gridDim.x);
}

}  // namespace sinew::simulator::cuda
