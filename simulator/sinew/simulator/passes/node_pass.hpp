#pragma once
// The node pass's loop body, written once for both engines: node i's internal force (the gather of
// its element-corner entries, in the fixed incidence order), its central-difference update and the
// checks on the result. The CPU's OpenMP chunks (engine/cpu_engine.cpp) and the CUDA node and tile
// kernels (cuda/node_kernels.cuh, cuda/tile_kernel.cuh) call these.
#include <cmath>
#include <cstdint>

#include "sinew/common/host_device.hpp"
#include "sinew/common/math.hpp"
#include "sinew/simulator/physics/central_difference.hpp"
#include "sinew/simulator/physics/element.hpp"

namespace sinew::simulator {

// The node tables of a model (EngineArrays::node_data()).
template <typename T>
struct NodeData {
  const T* inverse_mass;       // N, 1/kg (mass-scaled)
  const Vec3<T>* gravity;      // N, the physical weight (N); null without gravity
  const std::int32_t* offset;  // N + 1 incidence offsets (gather order)
  const std::int32_t* inc;     // entries into the element force buffer, in the gather order
  physics::CentralDifference<T> cd;
  std::int32_t n;  // N
};

template <typename T>
SINEW_HD_INLINE bool all_finite(const Vec3<T>& v) {
#if defined(__CUDA_ARCH__)
  return isfinite(v.x) && isfinite(v.y) && isfinite(v.z);
#else
  return std::isfinite(double(v.x)) && std::isfinite(double(v.y)) && std::isfinite(double(v.z));
#endif
}

// Node i's internal force f: Σ of its entries of the element force buffer (gather order).
template <typename T>
SINEW_HD_INLINE Vec3<T> node_internal_force(const NodeData<T>& d, const Vec3<T>* element_force,
                                            std::int32_t i) {
  return physics::gather_node_force(element_force, d.inc, d.offset[i], d.offset[i + 1]);
}

// u(n+1) of node i before its loads and constraints, from its internal force f, u(n) = ui,
// u(n−1) = upi and its inverse mass im (kGravity: plus its weight).
template <typename T, bool kGravity>
SINEW_HD_INLINE Vec3<T> advance_node(const NodeData<T>& d, std::int32_t i, const Vec3<T>& f,
                                     const Vec3<T>& ui, const Vec3<T>& upi, T im) {
  Vec3<T> g{T(0), T(0), T(0)};
  if constexpr (kGravity) g = d.gravity[i];
  (void)i;
  return physics::node_update<T, kGravity>(d.cd, im, f, g, ui, upi);
}

// ½ M |v|² of a node at u(n) (J), v = (u(n) − u(n−1)) / Δt in double: the term every kinetic
// energy sum adds (the blow-up test on both engines, Backend::energies()).
template <typename T>
SINEW_HD_INLINE double node_kinetic_energy(const Vec3<T>& ui, const Vec3<T>& upi, T im,
                                           double inv_dt) {
  const double vx = (double(ui.x) - double(upi.x)) * inv_dt;
  const double vy = (double(ui.y) - double(upi.y)) * inv_dt;
  const double vz = (double(ui.z) - double(upi.z)) * inv_dt;
  return 0.5 / double(im) * (vx * vx + vy * vy + vz * vz);
}

// The generic one-thread-per-node body: node i's internal force into f (Backend::internal_forces,
// the gather of the CPU's step). Launched by cpu_for_each and the CUDA forall kernel.
template <typename T>
struct GatherBody {
  NodeData<T> nodes;
  const Vec3<T>* element_force;
  Vec3<T>* f;
  SINEW_HD_INLINE void operator()(std::int32_t i) const {
    f[i] = node_internal_force(nodes, element_force, i);
  }
};

// The generic body that copies the vectors of listed nodes: to[k] = from[nodes[k]] (probes and
// reaction sets read only these from a device).
template <typename T>
struct CopyNodesBody {
  const std::int32_t* nodes;
  const Vec3<T>* from;
  Vec3<T>* to;
  SINEW_HD_INLINE void operator()(std::int32_t k) const { to[k] = from[nodes[k]]; }
};

}  // namespace sinew::simulator
