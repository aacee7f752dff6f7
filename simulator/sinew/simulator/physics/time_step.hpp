#pragma once
// Critical time-step estimate per element (physics-notes §4; docs/physics.md "Time step").
//   Δt_crit,e = h / c_e,   c_e = sqrt(M_e / ρ_e)
//   M_e = Σ_m w_m (λ_m + 2μ_m)                          weighted dilatational modulus, Pa
//       + Σ_muscles w σref (a_max·max|fa'| + fp'(x*)) / λopt   when muscles are simulated
//   ρ_e = Σ_m w_m ρ_m · mass_scaling                      weighted density, kg/m³
// Δt_crit = min_e Δt_crit,e; the engine uses safety_factor × Δt_crit (setup.hpp). h/c is the
// Courant length, not the exact limit: a free block of one-point cubes with lumped mass is stable
// up to ≈ 0.85 h/c_d at ν = 0.49 (0.98 at ν = 0.3), less with hourglass stiffness and under
// compression — hence a safety factor of 0.5 by default. (The Flanagan–Belytschko bound
// h/(√3 c_d) ≈ 0.577 h/c_d is always safe.)
#include "sinew/common/host_device.hpp"
#include "sinew/common/math.hpp"

namespace sinew::simulator::physics {

// h / sqrt(M/ρ), s. Returns +inf (as a huge value) when M ≤ 0.
template <typename T>
SINEW_HD_INLINE T critical_time_step(T h, T modulus, T density) {
  if (!(modulus > T(0))) return T(1e30);
  return h / std::sqrt(modulus / density);
}

// Fibre tangent modulus used in the estimate: w σref (a_max · 3.6 + fp'(x*)) / λopt, Pa.
template <typename T>
SINEW_HD_INLINE T muscle_tangent_modulus(T fraction, T reference_stress, T optimal_stretch,
                                         T max_activation, T passive_max_slope) {
  return fraction * reference_stress * (max_activation * T(3.6) + passive_max_slope) /
         optimal_stretch;
}

}  // namespace sinew::simulator::physics
