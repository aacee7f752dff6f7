#pragma once
// The element pass's loop body, written once for both engines (the CPU's OpenMP chunks in
// engine/cpu_engine.cpp and the CUDA element kernel in engine/cuda/element_kernels.cuh call it;
// the tiled kernel computes its elements from shared-memory windows with the same physics call).
//
// One element e: its node ids, parameter row and muscle entries (element_start: what the pass reads
// before the displacements, so a GPU kernel can issue these loads before it waits on the kernel
// that writes u), then u of its 8 nodes and physics::element_forces (element_finish): the nodal
// forces fe (N), J = det F and, with kEnergy, the strain, elastic and hourglass energies added to
// the caller's accumulators (J, double).
#include <array>
#include <cstdint>

#include "sinew/common/host_device.hpp"
#include "sinew/common/math.hpp"
#include "sinew/formats/model.hpp"
#include "sinew/simulator/physics/element.hpp"

namespace sinew::simulator {

// The element tables of a model, as device or host pointers (EngineArrays::element_data()).
template <typename T>
struct ElementData {
  const std::array<formats::Index, 8>* nodes;     // E × 8 node ids
  const std::int32_t* row;                        // E, parameter row of each element
  const physics::ElementRow<T>* rows;             // (μ, κ, k_HG) per row
  const std::int32_t* muscle_offset;              // E + 1 (CSR over the muscle entries), or null
  const std::int32_t* muscle_id;                  // per entry
  const T* muscle_fraction;                       // per entry, volume fraction w
  const Vec3<T>* muscle_fibre;                    // per entry, unit reference fibre a0
  const physics::MuscleParams<T>* muscle_params;  // per model muscle
  T h;                                            // m, voxel size
  std::int32_t elements;                          // E
};

// What element e's work reads besides the displacements and activations.
template <typename T>
struct ElementStart {
  std::int32_t ids[8];
  physics::ElementRow<T> row;
  physics::MuscleEntries<T> muscles;
};

template <typename T, bool kMuscle>
SINEW_HD_INLINE ElementStart<T> element_start(const ElementData<T>& d, std::int32_t e,
                                              const T* activation) {
  ElementStart<T> s;
#if defined(__CUDA_ARCH__)
  // Two 16-byte loads through the read-only path (the node ids never change during a run).
  const int4* np = reinterpret_cast<const int4*>(d.nodes + e);
  const int4 n0 = __ldg(np), n1 = __ldg(np + 1);
  const int ids[8] = {n0.x, n0.y, n0.z, n0.w, n1.x, n1.y, n1.z, n1.w};
  for (int a = 0; a < 8; ++a) s.ids[a] = ids[a];
#else
  for (int a = 0; a < 8; ++a) s.ids[a] = std::int32_t(d.nodes[e][std::size_t(a)]);
#endif
  s.row = d.rows[d.row[e]];
  s.muscles = {d.muscle_id, d.muscle_fraction, d.muscle_fibre, d.muscle_params, activation, 0, 0};
  if constexpr (kMuscle) {
    s.muscles.begin = d.muscle_offset[e];
    s.muscles.end = d.muscle_offset[e + 1];
  }
  return s;
}

// fe: the element's nodal forces at u (N × 3 per corner); returns J. strain, elastic, hourglass:
// running sums the element's energies are added to, term by term (kEnergy).
template <typename T, bool kElastic, bool kMuscle, bool kHourglass, bool kEnergy>
SINEW_HD_INLINE T element_finish(const ElementData<T>& d, const ElementStart<T>& s,
                                 const Vec3<T>* u, Vec3<T> (&fe)[8], double& strain,
                                 double& elastic, double& hourglass) {
  Vec3<T> ue[8];
#if defined(__CUDA_ARCH__)
#pragma unroll
#endif
  for (int a = 0; a < 8; ++a) ue[a] = u[s.ids[a]];
  return physics::element_forces<T, kElastic, kMuscle, kHourglass, kEnergy>(
      ue, d.h, s.row, s.muscles, fe, strain, elastic, hourglass);
}

}  // namespace sinew::simulator
