#pragma once
// Muscle fibre stress (physics-notes §2; Blemker, Pinsky, Delp 2005 for the curves).
//
// Convention (this project's; docs/physics.md): the muscle adds a NOMINAL fibre stress T (force per
// undeformed cross-section area, Pa) along the reference fibre direction a0 (unit):
//   λ = sqrt(a0 · C a0)                                   fibre stretch
//   T = σref · ( a(t) · fa(λ/λopt) + fp(λ/λopt) )         Pa
//   S_muscle = w · (T / λ) · a0 ⊗ a0                      Pa, w = the muscle's volume fraction
// so that P = F S_muscle gives a force T·A0 along the deformed fibre.
//
//   fa(x) = 9(x − 0.4)²        0.4 ≤ x ≤ 0.6
//           1 − 4(1 − x)²      0.6 < x < 1.4
//           9(x − 1.6)²        1.4 ≤ x ≤ 1.6
//           0                  elsewhere
//   fp(x) = 0                          x ≤ 1
//           P1 (exp(P2 (x − 1)) − 1)   1 < x < x*
//           fp(x*) + fp'(x*) (x − x*)  x ≥ x*            (continuous value and slope)
// Energy (S = 2 ∂W/∂C): W(λ) = σref λopt ∫_1^{λ/λopt} (a fa(x) + fp(x)) dx for a fixed activation
// a; the passive part is a true strain energy, the active one a potential only while a is fixed.
#include "sinew/common/host_device.hpp"
#include "sinew/common/math.hpp"

namespace sinew::simulator::physics {

template <typename T>
struct MuscleParams {
  T reference_stress;  // σref, Pa
  T optimal_stretch;   // λopt
  T p1, p2;            // passive curve
  T linear_stretch;    // x*
};

// Active force–length curve fa(x), dimensionless.
template <typename T>
SINEW_HD_INLINE T blemker_active(T x) {
  if (x < T(0.4) || x > T(1.6)) return T(0);
  if (x <= T(0.6)) return T(9) * (x - T(0.4)) * (x - T(0.4));
  if (x < T(1.4)) return T(1) - T(4) * (T(1) - x) * (T(1) - x);
  return T(9) * (x - T(1.6)) * (x - T(1.6));
}

// ∫_1^x fa(s) ds (x may be below 1: the integral is then negative), dimensionless.
template <typename T>
SINEW_HD_INLINE T blemker_active_integral(T x) {
  // Antiderivative G with G(1) = 0, piecewise; G is continuous.
  auto mid = [](T y) { return (y - T(1)) + T(4) / T(3) * (T(1) - y) * (T(1) - y) * (T(1) - y); };
  // mid(y) = ∫_1^y (1 − 4(1−s)²) ds
  if (x <= T(0.4)) {
    // ∫_1^0.4 = mid(0.6) − ∫_0.4^0.6 9(s−0.4)² ds
    return mid(T(0.6)) - T(3) * T(0.2) * T(0.2) * T(0.2);
  }
  if (x <= T(0.6))
    return mid(T(0.6)) - T(3) * ((T(0.6) - T(0.4)) * (T(0.6) - T(0.4)) * (T(0.6) - T(0.4)) -
                                 (x - T(0.4)) * (x - T(0.4)) * (x - T(0.4)));
  if (x < T(1.4)) return mid(x);
  const T at14 = mid(T(1.4));
  if (x <= T(1.6))
    return at14 + T(3) * ((x - T(1.6)) * (x - T(1.6)) * (x - T(1.6)) -
                          (T(1.4) - T(1.6)) * (T(1.4) - T(1.6)) * (T(1.4) - T(1.6)));
  return at14 + T(3) * T(0.2) * T(0.2) * T(0.2);
}

// Passive fibre curve fp(x), dimensionless.
template <typename T>
SINEW_HD_INLINE T passive_fibre(T x, T p1, T p2, T x_star) {
  if (x <= T(1)) return T(0);
  if (x < x_star) return p1 * (std::exp(p2 * (x - T(1))) - T(1));
  const T v = p1 * (std::exp(p2 * (x_star - T(1))) - T(1));
  const T slope = p1 * p2 * std::exp(p2 * (x_star - T(1)));
  return v + slope * (x - x_star);
}

// ∫_1^x fp(s) ds, dimensionless.
template <typename T>
SINEW_HD_INLINE T passive_fibre_integral(T x, T p1, T p2, T x_star) {
  if (x <= T(1)) return T(0);
  auto exp_part = [&](T y) { return p1 * ((std::exp(p2 * (y - T(1))) - T(1)) / p2 - (y - T(1))); };
  if (x < x_star) return exp_part(x);
  const T v = p1 * (std::exp(p2 * (x_star - T(1))) - T(1));
  const T slope = p1 * p2 * std::exp(p2 * (x_star - T(1)));
  const T d = x - x_star;
  return exp_part(x_star) + v * d + T(0.5) * slope * d * d;
}

// Largest slope of fp over [0, x*] and beyond: fp'(x*), dimensionless (used by time_step.hpp).
template <typename T>
SINEW_HD_INLINE T passive_fibre_max_slope(T p1, T p2, T x_star) {
  return p1 * p2 * std::exp(p2 * (x_star - T(1)));
}
// Largest |fa'| (at x = 0.6 and 1.4 from the outer parabolas: 18·0.2 = 3.6).
template <typename T>
SINEW_HD_INLINE T blemker_active_max_slope() {
  return T(3.6);
}

// Fibre stretch λ = sqrt(a0 · C a0).
template <typename T>
SINEW_HD_INLINE T fibre_stretch(const SymMat3<T>& c, const Vec3<T>& a0) {
  return std::sqrt(quadratic_form(c, a0));
}

// Nominal fibre stress T(λ), Pa.
template <typename T>
SINEW_HD_INLINE T muscle_nominal_stress(T stretch, T activation, const MuscleParams<T>& p) {
  const T x = stretch / p.optimal_stretch;
  return p.reference_stress *
         (activation * blemker_active(x) + passive_fibre(x, p.p1, p.p2, p.linear_stretch));
}

// Adds w · (T/λ) a0 ⊗ a0 to s. Returns T (Pa).
template <typename T>
SINEW_HD_INLINE T add_muscle_stress(const SymMat3<T>& c, const Vec3<T>& a0, T fraction,
                                    T activation, const MuscleParams<T>& p, SymMat3<T>& s) {
  const T stretch = fibre_stretch(c, a0);
  const T t = muscle_nominal_stress(stretch, activation, p);
  const T k = fraction * t / stretch;
  s.s[0] += k * a0.x * a0.x;
  s.s[1] += k * a0.y * a0.y;
  s.s[2] += k * a0.z * a0.z;
  s.s[3] += k * a0.y * a0.z;
  s.s[4] += k * a0.x * a0.z;
  s.s[5] += k * a0.x * a0.y;
  return t;
}

// Energy per unit reference volume, J/m³, of w · muscle at fixed activation, in two parts:
// the passive strain energy w σref λopt ∫_1^{λ/λopt} fp, stored in the tissue (≥ 0), and the
// active potential w σref λopt a ∫_1^{λ/λopt} fa, the work the contractile force would do back to
// the rest length: negative while the fibre is shorter than λopt (a contracting muscle), so it is
// no energy stored in the material (docs/physics.md §8).
template <typename T>
SINEW_HD_INLINE T muscle_passive_energy(const SymMat3<T>& c, const Vec3<T>& a0, T fraction,
                                        const MuscleParams<T>& p) {
  const T x = fibre_stretch(c, a0) / p.optimal_stretch;
  return fraction * p.reference_stress * p.optimal_stretch *
         passive_fibre_integral(x, p.p1, p.p2, p.linear_stretch);
}
template <typename T>
SINEW_HD_INLINE T muscle_active_energy(const SymMat3<T>& c, const Vec3<T>& a0, T fraction,
                                       T activation, const MuscleParams<T>& p) {
  const T x = fibre_stretch(c, a0) / p.optimal_stretch;
  return fraction * p.reference_stress * p.optimal_stretch * activation *
         blemker_active_integral(x);
}

// Their sum, J/m³: w σref λopt ∫_1^{λ/λopt} (a fa + fp), the potential whose 2 ∂/∂C is the muscle
// stress at fixed activation. With activation = 0 this is the passive strain energy.
template <typename T>
SINEW_HD_INLINE T muscle_energy(const SymMat3<T>& c, const Vec3<T>& a0, T fraction, T activation,
                                const MuscleParams<T>& p) {
  return muscle_passive_energy(c, a0, fraction, p) +
         muscle_active_energy(c, a0, fraction, activation, p);
}

}  // namespace sinew::simulator::physics
