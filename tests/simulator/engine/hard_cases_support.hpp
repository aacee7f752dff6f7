#pragma once
// Independent references for the hard-case suite (hard_cases_test.cpp): closed forms of the TLED
// neo-Hookean for homogeneous states and the muscle curves, written out from physics-notes §2 and
// §7 rather than taken from the engine's physics headers, plus the energy and momentum bookkeeping
// the cases check. SI units.
#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/backend.hpp"

namespace sinew::simulator::testing {

// Principal stretches (l1, l2, l3) of a homogeneous state.
struct Stretches {
  double l1 = 1, l2 = 1, l3 = 1;
  double j() const { return l1 * l2 * l3; }
  double i1() const { return l1 * l1 + l2 * l2 + l3 * l3; }
};

// Principal Cauchy stress σ_i = μ J^(−5/3)(l_i² − I1/3) + κ(J − 1) (physics-notes §2), Pa.
inline double cauchy_principal(double mu, double kappa, const Stretches& s, int i) {
  const double l = i == 0 ? s.l1 : (i == 1 ? s.l2 : s.l3);
  return mu * std::pow(s.j(), -5.0 / 3) * (l * l - s.i1() / 3) + kappa * (s.j() - 1);
}
// Principal nominal stress P_i = σ_i J / l_i (force per undeformed area), Pa.
inline double nominal_principal(double mu, double kappa, const Stretches& s, int i) {
  const double l = i == 0 ? s.l1 : (i == 1 ? s.l2 : s.l3);
  return cauchy_principal(mu, kappa, s, i) * s.j() / l;
}
// W = μ/2 (J^(−2/3) I1 − 3) + κ/2 (J − 1)², J/m³ of reference volume.
inline double energy_density(double mu, double kappa, const Stretches& s) {
  return 0.5 * mu * (std::pow(s.j(), -2.0 / 3) * s.i1() - 3) +
         0.5 * kappa * (s.j() - 1) * (s.j() - 1);
}
// Lateral stretch of uniaxial stress along 1 (σ2 = σ3 = 0) at axial stretch l1, by bisection.
inline double lateral_stretch(double mu, double kappa, double l1) {
  double lo = 0.05, hi = 5;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (cauchy_principal(mu, kappa, {l1, mid, mid}, 1) > 0 ? hi : lo) = mid;
  }
  return 0.5 * (lo + hi);
}

// Blemker active force–length curve and the exponential-linear passive fibre curve (notes §2).
inline double active_fl(double x) {
  if (x < 0.4 || x > 1.6) return 0;
  if (x <= 0.6) return 9 * (x - 0.4) * (x - 0.4);
  if (x < 1.4) return 1 - 4 * (1 - x) * (1 - x);
  return 9 * (x - 1.6) * (x - 1.6);
}
inline double passive_fl(double x, double p1 = 0.05, double p2 = 6.6, double xs = 1.4) {
  if (x <= 1) return 0;
  if (x < xs) return p1 * (std::exp(p2 * (x - 1)) - 1);
  return p1 * (std::exp(p2 * (xs - 1)) - 1) + p1 * p2 * std::exp(p2 * (xs - 1)) * (x - xs);
}

// Lumped nodal masses of a model whose every element is full (Σ w_m ρ_m V0 / 8 per corner), kg.
inline std::vector<double> lumped_masses(const formats::Model& m, double mass_scaling = 1) {
  std::vector<double> mass(m.node_count(), 0.0);
  const double h = m.grid.voxel_size, v0 = h * h * h;
  for (std::size_t e = 0; e < m.element_count(); ++e) {
    double rho = 0;
    for (auto k = m.material_offsets[e]; k < m.material_offsets[e + 1]; ++k)
      rho += m.material_fractions[std::size_t(k)] *
             m.materials[std::size_t(m.material_ids[std::size_t(k)])].density;
    for (auto n : m.element_nodes[e]) mass[std::size_t(n)] += rho * mass_scaling * v0 / 8;
  }
  return mass;
}

// Linear momentum Σ m v and angular momentum Σ m x × v about the origin, with v = (u(n) −
// u(n−1))/Δt and x = X + u(n−1): the pair central differences conserve exactly for internal forces
// whose torque vanishes (F S Fᵀ symmetric; hourglass forces q ⊗ q), so any drift is round-off.
struct Momenta {
  std::array<double, 3> linear{0, 0, 0}, angular{0, 0, 0};
};
inline Momenta momenta(const formats::Model& m, const std::vector<double>& mass, Backend& b) {
  const auto u = b.displacements();
  const auto v = b.velocities();
  Momenta p;
  for (std::size_t i = 0; i < m.node_count(); ++i) {
    const auto x0 = m.node_position(formats::Index(i));
    double x[3], w[3];
    for (int k = 0; k < 3; ++k) {
      w[k] = v[3 * i + std::size_t(k)];
      x[k] = x0[std::size_t(k)] + u[3 * i + std::size_t(k)] - w[k] * b.dt();
      p.linear[std::size_t(k)] += mass[i] * w[k];
    }
    p.angular[0] += mass[i] * (x[1] * w[2] - x[2] * w[1]);
    p.angular[1] += mass[i] * (x[2] * w[0] - x[0] * w[2]);
    p.angular[2] += mass[i] * (x[0] * w[1] - x[1] * w[0]);
  }
  return p;
}

// Seeded random initial velocities (uniform in ±amplitude per component) with the rigid-body part
// removed: zero linear and zero angular momentum about the centre of mass, so a free body only
// vibrates. Returned as N × 3.
inline std::vector<std::array<double, 3>> random_vibration(const formats::Model& m,
                                                           const std::vector<double>& mass,
                                                           double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> d(-amplitude, amplitude);
  const std::size_t n = m.node_count();
  std::vector<std::array<double, 3>> v(n);
  for (auto& vi : v) vi = {d(rng), d(rng), d(rng)};
  double mt = 0, c[3] = {0, 0, 0}, p[3] = {0, 0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    const auto x = m.node_position(formats::Index(i));
    mt += mass[i];
    for (int k = 0; k < 3; ++k) {
      c[k] += mass[i] * x[std::size_t(k)];
      p[k] += mass[i] * v[i][std::size_t(k)];
    }
  }
  for (int k = 0; k < 3; ++k) c[k] /= mt;
  for (auto& vi : v)
    for (int k = 0; k < 3; ++k) vi[std::size_t(k)] -= p[k] / mt;
  // Angular momentum L and inertia tensor I about the centre; subtract ω × r with I ω = L.
  double l[3] = {0, 0, 0}, in[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  for (std::size_t i = 0; i < n; ++i) {
    const auto x = m.node_position(formats::Index(i));
    const double r[3] = {x[0] - c[0], x[1] - c[1], x[2] - c[2]};
    const auto& w = v[i];
    l[0] += mass[i] * (r[1] * w[2] - r[2] * w[1]);
    l[1] += mass[i] * (r[2] * w[0] - r[0] * w[2]);
    l[2] += mass[i] * (r[0] * w[1] - r[1] * w[0]);
    const double rr = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) in[a][b] += mass[i] * ((a == b ? rr : 0) - r[a] * r[b]);
  }
  // Solve I ω = L (Cramer).
  auto det3 = [](const double a[3][3]) {
    return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
           a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  };
  const double di = det3(in);
  double om[3];
  for (int k = 0; k < 3; ++k) {
    double a[3][3];
    for (int r = 0; r < 3; ++r)
      for (int s = 0; s < 3; ++s) a[r][s] = s == k ? l[r] : in[r][s];
    om[k] = det3(a) / di;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const auto x = m.node_position(formats::Index(i));
    const double r[3] = {x[0] - c[0], x[1] - c[1], x[2] - c[2]};
    v[i][0] -= om[1] * r[2] - om[2] * r[1];
    v[i][1] -= om[2] * r[0] - om[0] * r[2];
    v[i][2] -= om[0] * r[1] - om[1] * r[0];
  }
  return v;
}

inline double mechanical_energy(const Energies& e) {
  return e.kinetic + e.strain + e.hourglass;
}

inline bool all_finite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

}  // namespace sinew::simulator::testing
