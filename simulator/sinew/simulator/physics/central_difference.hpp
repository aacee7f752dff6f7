#pragma once
// Centred central-difference update with lumped mass and mass-proportional damping C = αM
// (Miller et al. 2007; NiftySim; physics-notes §4):
//   u(n+1) = A (R − f) + B u(n) + Cc u(n−1)
//   A  = 1 / (M/Δt² + αM/(2Δt))  = Δt² / (M (1 + αΔt/2))
//   B  = 2MA/Δt²                 = 2 / (1 + αΔt/2)
//   Cc = αMA/(2Δt) − B/2         = −(1 − αΔt/2) / (1 + αΔt/2)
// B and Cc do not depend on the mass; A = a_over_inverse_mass · (1/M). R: external force, f:
// internal force (N); u: displacement (m). Every under-damped mode decays as exp(−αt/2), by the
// exact per-step factor sqrt((1 − αΔt/2)/(1 + αΔt/2)). The stable step is that of the undamped
// scheme.
#include "sinew/common/host_device.hpp"
#include "sinew/common/math.hpp"

namespace sinew::simulator::physics {

template <typename T>
struct CentralDifference {
  T a_over_inverse_mass;  // Δt² / (1 + αΔt/2), s²: A = this / M
  T b;                    // B
  T c;                    // Cc
};

template <typename T>
SINEW_HD_INLINE CentralDifference<T> central_difference(double dt, double alpha) {
  const double d = 1.0 + 0.5 * alpha * dt;
  return {T(dt * dt / d), T(2.0 / d), T(-(1.0 - 0.5 * alpha * dt) / d)};
}

// The per-step amplitude factor of an under-damped mode (ω Δt small): sqrt((1 − αΔt/2)/(1 +
// αΔt/2)).
SINEW_HD_INLINE double damping_step_factor(double dt, double alpha) {
  return std::sqrt((1.0 - 0.5 * alpha * dt) / (1.0 + 0.5 * alpha * dt));
}

// One node: u(n+1) = A (R − f) + B u(n) + Cc u(n−1), A = cd.a_over_inverse_mass · inverse_mass
// (evaluated as Cc u(n−1) + (B u(n) + A (R − f)) with multiply_add: one order in every kernel, and on
// the host the same value as the expression left to right).
template <typename T>
SINEW_HD_INLINE Vec3<T> central_difference_update(const CentralDifference<T>& cd, T inverse_mass,
                                                  const Vec3<T>& r_minus_f, const Vec3<T>& u,
                                                  const Vec3<T>& u_prev) {
  const T a = cd.a_over_inverse_mass * inverse_mass;
  Vec3<T> next;
  for (int k = 0; k < 3; ++k)
    next[k] = multiply_add(cd.c, u_prev[k], multiply_add(cd.b, u[k], a * r_minus_f[k]));
  return next;
}

// Where a node coasts to with no force: u(n+1) = B u(n) + Cc u(n−1) (its velocity kept, damped),
// as central_difference_update with R − f = 0 (the lips' contact predicts a partner with it).
template <typename T>
SINEW_HD_INLINE Vec3<T> coasting(const CentralDifference<T>& cd, const Vec3<T>& u,
                                 const Vec3<T>& u_prev) {
  Vec3<T> next;
  for (int k = 0; k < 3; ++k) next[k] = multiply_add(cd.c, u_prev[k], cd.b * u[k]);
  return next;
}

}  // namespace sinew::simulator::physics
