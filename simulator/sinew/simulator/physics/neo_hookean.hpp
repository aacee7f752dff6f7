#pragma once
// TLED neo-Hookean material (physics-notes §2; Miller et al. 2007; NiftySim):
//   W = μ/2 (Ī1 − 3) + κ/2 (J − 1)²,  Ī1 = J^(−2/3) I1,  I1 = tr C   (J/m³ of reference volume)
//   S = μ J^(−2/3) (I − (I1/3) C⁻¹) + κ J (J − 1) C⁻¹                (Pa, 2nd Piola–Kirchhoff)
//   μ = E / (2(1+ν)),  κ = E / (3(1−2ν)),  λ + 2μ = κ + 4μ/3.
// Not FEBio's "neo-Hookean" (μ/2(I1−3) − μ ln J + λ/2 (ln J)²).
//
// Multi-material elements: S = Σ_m w_m S_m(C). Because S is linear in (μ, κ), this equals S with
// μ = Σ w_m μ_m, κ = Σ w_m κ_m, which is how the engine evaluates it (one call per element).
#include "sinew/common/host_device.hpp"
#include "sinew/common/math.hpp"

namespace sinew::simulator::physics {

// S(C) with J = det F passed in (the caller has F; J = sqrt(det C) would lose the sign).
template <typename T>
SINEW_HD_INLINE SymMat3<T> neo_hookean_stress(const SymMat3<T>& c, T j, T mu, T kappa) {
  const SymMat3<T> c_inv = inverse(c);
  const T cbrt_j = std::cbrt(j);
  const T j_m23 = T(1) / (cbrt_j * cbrt_j);
  const T i1 = trace(c);
  const T a = mu * j_m23;
  const T b = kappa * j * (j - T(1)) - a * i1 / T(3);
  SymMat3<T> s;
  for (int k = 0; k < 6; ++k) s.s[k] = b * c_inv.s[k];
  s.s[0] += a;
  s.s[1] += a;
  s.s[2] += a;
  return s;
}

// W(C), J/m³ (per unit reference volume).
template <typename T>
SINEW_HD_INLINE T neo_hookean_energy(const SymMat3<T>& c, T j, T mu, T kappa) {
  const T cbrt_j = std::cbrt(j);
  const T j_m23 = T(1) / (cbrt_j * cbrt_j);
  return T(0.5) * mu * (j_m23 * trace(c) - T(3)) + T(0.5) * kappa * (j - T(1)) * (j - T(1));
}

// Dilatational (p-wave) modulus λ + 2μ = κ + 4μ/3, Pa.
template <typename T>
SINEW_HD_INLINE T p_wave_modulus(T mu, T kappa) {
  return kappa + T(4) * mu / T(3);
}

}  // namespace sinew::simulator::physics
