#pragma once
// The per-element and per-node work of one TLED step, written once for every backend (CPU loop
// bodies and CUDA kernels call these; docs/cuda-backend.md). Pure SINEW_HD functions of plain
// values and pointers: no containers, no allocation.
//
// Element (voxel cube of side h, one Gauss point; hex8.hpp, neo_hookean.hpp, muscle.hpp,
// hourglass.hpp):
//   F = I + Σ_a u_a ⊗ ∇0N_a,  J = det F,  C = FᵀF
//   S = S_neo-Hookean(C, J; μ, κ) + Σ_muscle entries w (T/λ) a0 ⊗ a0       Pa
//   f_a = V0 F S ∇0N_a (+ hourglass forces k Σα γα(a) q(α))                N
//   strain energy V0 (W_nH + Σ W_muscle), hourglass energy ½ k Σ q²        J (double)
//   elastic energy V0 (W_nH + Σ W_muscle,passive) ≥ 0, stored in the material  J (double)
//   (the strain energy without the active muscle potential, negative while a muscle contracts)
// μ, κ are the element's weighted moduli (S is linear in them); effects that are off are
// template flags, so a kernel specialised for an effect set carries no branch for the others.
#include <cstdint>

#include "sinew/common/host_device.hpp"
#include "sinew/common/math.hpp"
#include "sinew/simulator/physics/central_difference.hpp"
#include "sinew/simulator/physics/hex8.hpp"
#include "sinew/simulator/physics/hourglass.hpp"
#include "sinew/simulator/physics/muscle.hpp"
#include "sinew/simulator/physics/neo_hookean.hpp"
#include "sinew/simulator/physics/sliding.hpp"

namespace sinew::simulator::physics {

// The element's parameter row: weighted μ, κ (Pa; 0 when elasticity is off) and hourglass
// stiffness k (N/m).
template <typename T>
struct ElementRow {
  T mu, kappa, hourglass_k;
};

// The muscle entries of one element: entries [begin, end) of per-entry arrays (muscle id, volume
// fraction w, unit reference fibre a0) and per-muscle arrays (parameters, activation a ∈ [0, 1]).
template <typename T>
struct MuscleEntries {
  const std::int32_t* muscle;
  const T* fraction;
  const Vec3<T>* fibre;
  const MuscleParams<T>* params;
  const T* activation;
  std::int64_t begin, end;
};

// What the element pass reports besides the forces.
template <typename T>
struct ElementOutcome {
  T j;               // det F
  double strain;     // J, V0 (W_nH + Σ W_muscle) when kEnergy, else 0
  double elastic;    // J, V0 (W_nH + Σ W_muscle,passive) when kEnergy, else 0
  double hourglass;  // J, ½ k Σ q² when kEnergy and kHourglass, else 0
};

// S at (C, J) and, when kEnergy, its energies term by term (W in J/m³; scale = V0 for energies in
// J, 1 for densities): `energy += double(scale · W)` with W = W_nH + Σ W_muscle (passive + active
// at the current activation), and `elastic += ` the same without the active muscle terms.
template <typename T, bool kElastic, bool kMuscle, bool kEnergy>
SINEW_HD_INLINE SymMat3<T> element_stress(const SymMat3<T>& cg, T j, const ElementRow<T>& row,
                                          const MuscleEntries<T>& muscles, T scale, double& energy,
                                          double& elastic) {
  SymMat3<T> s = sym_zero<T>();
  if constexpr (kElastic) {
    s = neo_hookean_stress(cg, j, row.mu, row.kappa);
    if constexpr (kEnergy) {
      const double w = double(scale * neo_hookean_energy(cg, j, row.mu, row.kappa));
      energy += w;
      elastic += w;
    }
  }
  if constexpr (kMuscle) {
    for (std::int64_t k = muscles.begin; k < muscles.end; ++k) {
      const auto m = muscles.muscle[k];
      add_muscle_stress(cg, muscles.fibre[k], muscles.fraction[k], muscles.activation[m],
                        muscles.params[m], s);
      if constexpr (kEnergy) {
        const double passive =
            double(scale * muscle_passive_energy(cg, muscles.fibre[k], muscles.fraction[k],
                                                 muscles.params[m]));
        const double active =
            double(scale * muscle_active_energy(cg, muscles.fibre[k], muscles.fraction[k],
                                                muscles.activation[m], muscles.params[m]));
        energy += passive;
        energy += active;
        elastic += passive;
      }
    }
  }
  (void)scale;
  (void)energy;
  (void)elastic;
  (void)muscles;
  return s;
}

// The whole element: nodal displacements u (m) -> nodal forces fe (N); returns J. When kEnergy,
// adds its strain energy to `strain`, its elastic energy to `elastic` and (kHourglass) its
// hourglass energy to `hourglass` (J) term by term, so a caller summing many elements into one
// accumulator gets the same order as here.
template <typename T, bool kElastic, bool kMuscle, bool kHourglass, bool kEnergy>
SINEW_HD_INLINE T element_forces(const Vec3<T> (&u)[8], T h, const ElementRow<T>& row,
                                 const MuscleEntries<T>& muscles, Vec3<T> (&fe)[8], double& strain,
                                 double& elastic, double& hourglass) {
  const Mat3<T> f = hex8_deformation_gradient(u, h);
  Vec3<T> q[4];  // hourglass projections, taken before the stress so that u is no longer needed
  if constexpr (kHourglass) hourglass_projections(u, q);
  const T j = determinant(f);
  const SymMat3<T> cg = transpose_product(f);
  const T v0 = h * h * h;
  const SymMat3<T> s =
      element_stress<T, kElastic, kMuscle, kEnergy>(cg, j, row, muscles, v0, strain, elastic);
  hex8_nodal_forces(f, s, h, fe);
  if constexpr (kHourglass)
    hourglass += double(add_hourglass_projection_forces(q, row.hourglass_k, fe, kEnergy));
  (void)hourglass;
  (void)q;
  return j;
}

// The same for one element on its own: J and its energies in an ElementOutcome.
template <typename T, bool kElastic, bool kMuscle, bool kHourglass, bool kEnergy>
SINEW_HD_INLINE ElementOutcome<T> element_forces(const Vec3<T> (&u)[8], T h,
                                                 const ElementRow<T>& row,
                                                 const MuscleEntries<T>& muscles,
                                                 Vec3<T> (&fe)[8]) {
  ElementOutcome<T> out{T(0), 0.0, 0.0, 0.0};
  out.j = element_forces<T, kElastic, kMuscle, kHourglass, kEnergy>(
      u, h, row, muscles, fe, out.strain, out.elastic, out.hourglass);
  return out;
}

// Output fields of one element at u: J, Cauchy stress (Pa) and energy density (J/m³, hourglass
// excluded).
template <typename T, bool kElastic, bool kMuscle>
SINEW_HD_INLINE void element_field(const Vec3<T> (&u)[8], T h, const ElementRow<T>& row,
                                   const MuscleEntries<T>& muscles, T& j, SymMat3<T>& sigma,
                                   double& energy_density) {
  const Mat3<T> f = hex8_deformation_gradient(u, h);
  j = determinant(f);
  const SymMat3<T> cg = transpose_product(f);
  energy_density = 0;
  double elastic_density = 0;  // not an output field
  const SymMat3<T> s = element_stress<T, kElastic, kMuscle, true>(cg, j, row, muscles, T(1),
                                                                  energy_density, elastic_density);
  sigma = cauchy_stress(f, s, j);
}

// Internal force of a node: the sum of its (element, corner) entries of the per-element force
// buffer, in the order listed (entries [begin, end) of `incidence`, each e·8 + corner).
template <typename T>
SINEW_HD_INLINE Vec3<T> gather_node_force(const Vec3<T>* element_force,
                                          const std::int32_t* incidence, std::int64_t begin,
                                          std::int64_t end) {
  Vec3<T> s{T(0), T(0), T(0)};
  for (std::int64_t k = begin; k < end; ++k) s += element_force[incidence[k]];
  return s;
}

// Central-difference update of one node from its internal force f and (kGravity) its weight g:
// R − f = g − f. Returns u(n+1) before constraints.
template <typename T, bool kGravity>
SINEW_HD_INLINE Vec3<T> node_update(const CentralDifference<T>& cd, T inverse_mass,
                                    const Vec3<T>& f, const Vec3<T>& gravity, const Vec3<T>& u,
                                    const Vec3<T>& u_prev) {
  Vec3<T> r = -f;
  if constexpr (kGravity) r += gravity;
  (void)gravity;
  return central_difference_update(cd, inverse_mass, r, u, u_prev);
}

// A nodal force fn (N) added after the update: u(n+1) += A fn, A = cd.a_over_inverse_mass / M.
template <typename T>
SINEW_HD_INLINE void add_nodal_force(const CentralDifference<T>& cd, T inverse_mass,
                                     const Vec3<T>& fn, Vec3<T>& u_next) {
  const T a = cd.a_over_inverse_mass * inverse_mass;
  for (int k = 0; k < 3; ++k) u_next[k] = multiply_add(a, fn[k], u_next[k]);
}

// Prescribed displacement: the selected components take c · value (m).
template <typename T>
SINEW_HD_INLINE void prescribe(T c, const Vec3<T>& value, const bool (&components)[3], Vec3<T>& u) {
  for (int d = 0; d < 3; ++d)
    if (components[d]) u[d] = c * value[d];
}

}  // namespace sinew::simulator::physics
