// Unit tests of the pure physics functions (physics/*.hpp): closed forms and finite differences.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "sinew/common/math.hpp"
#include "sinew/simulator/physics/central_difference.hpp"
#include "sinew/simulator/physics/element.hpp"
#include "sinew/simulator/physics/hex8.hpp"
#include "sinew/simulator/physics/hourglass.hpp"
#include "sinew/simulator/physics/muscle.hpp"
#include "sinew/simulator/physics/neo_hookean.hpp"
#include "sinew/simulator/physics/sliding.hpp"
#include "sinew/simulator/physics/time_step.hpp"

namespace sinew::simulator::physics {
namespace {

using V = Vec3<double>;

// Reference coordinates of the cube's nodes, side h, corner at the origin.
void cube_nodes(double h, V (&x)[8]) {
  for (int a = 0; a < 8; ++a)
    x[a] = {h * (hex8_sign(a, 0) + 1) / 2, h * (hex8_sign(a, 1) + 1) / 2,
            h * (hex8_sign(a, 2) + 1) / 2};
}

TEST(Hex8, CornerOrderMatchesModelConvention) {
  // formats/model.hpp: 0:(0,0,0) 1:(1,0,0) 2:(1,1,0) 3:(0,1,0) 4:(0,0,1) 5:(1,0,1) 6:(1,1,1)
  // 7:(0,1,1)
  const int d[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                       {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  for (int a = 0; a < 8; ++a)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(hex8_sign(a, k), 2 * d[a][k] - 1);
}

TEST(Hex8, LinearFieldGivesItsGradientExactly) {
  const double h = 0.37e-3;
  V x[8];
  cube_nodes(h, x);
  const Mat3d g = {{{0.1, -0.2, 0.05}, {0.3, 0.02, -0.1}, {-0.07, 0.11, -0.15}}};
  V u[8];
  for (int a = 0; a < 8; ++a) u[a] = g * x[a] + V{1e-4, -2e-4, 3e-4};  // + a translation
  const Mat3d f = hex8_deformation_gradient(u, h);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(f(i, j), (i == j) + g(i, j), 1e-14);
  // ∇N sums to zero and V0 Σ_a ∇N_a ⊗ X_a = V0 I.
  for (int k = 0; k < 3; ++k) {
    double s = 0;
    for (int a = 0; a < 8; ++a) s += hex8_gradient(a, h)[k];
    EXPECT_NEAR(s, 0.0, 1e-12 / h);
  }
}

TEST(Hourglass, CubeShapeVectorsAreTheBaseVectorsAndOrthogonalToLinearFields) {
  const double h = 2e-3;
  V x[8], g[8];
  cube_nodes(h, x);
  for (int a = 0; a < 8; ++a) g[a] = hex8_gradient(a, h);
  double gamma[4][8];
  hourglass_shape_vectors(x, g, gamma);
  for (int al = 0; al < 4; ++al)
    for (int a = 0; a < 8; ++a) EXPECT_NEAR(gamma[al][a], hourglass_base(al, a), 1e-15);
  // No force and no energy for a linear field.
  const Mat3d grad = {{{0.3, 0.1, 0}, {-0.2, 0.05, 0.4}, {0.1, 0.2, -0.3}}};
  V u[8], f[8] = {};
  for (int a = 0; a < 8; ++a) u[a] = grad * x[a] + V{1e-3, 0, -1e-3};
  const double e = add_hourglass_forces(u, 1234.5, f, true);
  EXPECT_NEAR(e, 0.0, 1e-18);
  for (int a = 0; a < 8; ++a) EXPECT_NEAR(norm(f[a]), 0.0, 1e-12);
  // A pure hourglass mode: u_x = Γ0 (ξη) · d gives q = |Γ0|² d = 8d and energy ½ k (8d)² = 32 k d².
  V uh[8], fh[8] = {};
  const double d = 1e-5;
  for (int a = 0; a < 8; ++a) uh[a] = {d * hourglass_base(0, a), 0, 0};
  EXPECT_NEAR(add_hourglass_forces(uh, 100.0, fh, true), 32 * 100.0 * d * d, 1e-20);
  EXPECT_NEAR(fh[2].x, 100.0 * 8 * d * hourglass_base(0, 2), 1e-15);
  EXPECT_NEAR(hourglass_stiffness(0.1, 2000.0, 1e-3), 0.1 * 2000 * 3e-3 / 16, 1e-15);
}

TEST(Hourglass, ForcesEqualTheConstantMatrixTimesDisplacements) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> r(-1e-4, 1e-4);
  V u[8], f[8] = {};
  for (auto& v : u) v = {r(rng), r(rng), r(rng)};
  const double k = 37.5;
  const double e = add_hourglass_forces(u, k, f, true);
  double e_matrix = 0;
  for (int a = 0; a < 8; ++a) {
    V hu{0, 0, 0};
    for (int b = 0; b < 8; ++b) hu += double(hourglass_matrix(a, b)) * u[b];
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(f[a][i], k * hu[i], 1e-15);
    e_matrix += 0.5 * k * dot(u[a], hu);
  }
  EXPECT_NEAR(e, e_matrix, 1e-12 * e);
  // H is symmetric, its rows sum to zero (translations) and its diagonal is 4.
  for (int a = 0; a < 8; ++a) {
    int row = 0;
    for (int b = 0; b < 8; ++b) {
      EXPECT_EQ(hourglass_matrix(a, b), hourglass_matrix(b, a));
      row += hourglass_matrix(a, b);
    }
    EXPECT_EQ(row, 0);
    EXPECT_EQ(hourglass_matrix(a, a), 4);
  }
}

TEST(NeoHookean, UniaxialPrincipalStressesMatchClosedForm) {
  const double mu = 1000, nu = 0.49;
  const double e = 2 * mu * (1 + nu), kappa = e / (3 * (1 - 2 * nu));
  const double l1 = 1.5, l2 = 0.820731;
  const Mat3d f = {{{l1, 0, 0}, {0, l2, 0}, {0, 0, l2}}};
  const double j = determinant(f);
  const SymMat3<double> s = neo_hookean_stress(transpose_product(f), j, mu, kappa);
  const SymMat3<double> sigma = cauchy_stress(f, s, j);
  const double i1 = l1 * l1 + 2 * l2 * l2;
  const double s1 = mu * std::pow(j, -5.0 / 3) * (l1 * l1 - i1 / 3) + kappa * (j - 1);
  const double s2 = mu * std::pow(j, -5.0 / 3) * (l2 * l2 - i1 / 3) + kappa * (j - 1);
  EXPECT_NEAR(sigma.s[0], s1, 1e-9 * std::abs(s1));
  EXPECT_NEAR(sigma.s[1], s2, 1e-9);
  // notes §7: at this lateral stretch σ22 ≈ 0 and P11 = σ11 J / λ1 = 1043.71 Pa.
  EXPECT_NEAR(sigma.s[1], 0.0, 0.1);
  EXPECT_NEAR(sigma.s[0] * j / l1, 1043.71, 0.1);
  // Undeformed: no stress.
  const SymMat3<double> s0 = neo_hookean_stress(sym_identity<double>(), 1.0, mu, kappa);
  for (double v : s0.s) EXPECT_NEAR(v, 0.0, 1e-12);
}

// f_a = ∂(V0 W)/∂u_a by central differences, for random deformations of one cube element with
// neo-Hookean (several materials), the passive and active muscle (fixed activation) and hourglass.
struct FdCase {
  double mu, kappa, khg;
  bool muscle;
  double activation;
  double stretch;  // target fibre stretch of the base deformation
};

double element_energy(const V (&u)[8], double h, const FdCase& c, const V& a0,
                      const MuscleParams<double>& mp) {
  const Mat3d f = hex8_deformation_gradient(u, h);
  const double j = determinant(f);
  const SymMat3<double> cg = transpose_product(f);
  double w = neo_hookean_energy(cg, j, c.mu, c.kappa);
  if (c.muscle) w += muscle_energy(cg, a0, 0.8, c.activation, mp);
  double e = h * h * h * w;
  V dummy[8] = {};
  if (c.khg > 0) e += add_hourglass_forces(u, c.khg, dummy, true);
  return e;
}

void element_forces(const V (&u)[8], double h, const FdCase& c, const V& a0,
                    const MuscleParams<double>& mp, V (&f)[8]) {
  const Mat3d fm = hex8_deformation_gradient(u, h);
  const double j = determinant(fm);
  const SymMat3<double> cg = transpose_product(fm);
  SymMat3<double> s = neo_hookean_stress(cg, j, c.mu, c.kappa);
  if (c.muscle) add_muscle_stress(cg, a0, 0.8, c.activation, mp, s);
  hex8_nodal_forces(fm, s, h, f);
  if (c.khg > 0) add_hourglass_forces(u, c.khg, f, false);
}

TEST(ElementForces, EqualTheEnergyGradientByFiniteDifferences) {
  const double h = 1e-3;
  const MuscleParams<double> mp{5e4, 1.0, 0.05, 6.6, 1.4};
  const FdCase cases[] = {
      {1000, 1000 * 2 * 1.49 / (3 * 0.02), 0, false, 0, 1.0},      // ν = 0.49
      {340, 340 * 2 * 1.3 / (3 * 0.4), 0, false, 0, 1.0},          // ν = 0.3
      {16100, 16100 * 2 * 1.499 / (3 * 0.002), 0, false, 0, 1.0},  // ν = 0.499
      {1000, 1e5, 30.0, false, 0, 1.0},                            // + hourglass
      {1000, 1e5, 0, true, 0.0, 1.2},                              // passive muscle
      {1000, 1e5, 0, true, 0.0, 1.55},                             // passive, linear part
      {1000, 1e5, 0, true, 0.7, 0.9},                              // active at fixed a
      {1000, 1e5, 10.0, true, 0.3, 1.3},                           // everything
  };
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> small(-0.08, 0.08);
  int tested = 0;
  double worst = 0;
  for (const auto& c : cases) {
    for (int trial = 0; trial < 5; ++trial) {
      V a0{small(rng) + 1, small(rng), small(rng)};
      a0 = (1 / norm(a0)) * a0;
      // Base deformation: stretch along a0 by c.stretch plus random perturbation.
      V x[8], u[8];
      cube_nodes(h, x);
      for (int a = 0; a < 8; ++a) {
        const double along = dot(a0, x[a]) * (c.stretch - 1);
        u[a] = along * a0 + V{small(rng) * h, small(rng) * h, small(rng) * h};
      }
      V f[8];
      element_forces(u, h, c, a0, mp, f);
      double fmax = 0;
      for (auto& v : f) fmax = std::max(fmax, norm(v));
      const double eps = 1e-7 * h;
      for (int a = 0; a < 8; ++a)
        for (int k = 0; k < 3; ++k) {
          V up[8], um[8];
          for (int b = 0; b < 8; ++b) up[b] = um[b] = u[b];
          up[a][k] += eps;
          um[a][k] -= eps;
          const double g =
              (element_energy(up, h, c, a0, mp) - element_energy(um, h, c, a0, mp)) / (2 * eps);
          const double err = std::abs(g - f[a][k]) / fmax;
          worst = std::max(worst, err);
          EXPECT_LT(err, 1e-6) << "case mu=" << c.mu << " muscle=" << c.muscle << " node " << a
                               << " dir " << k << ": fd " << g << " vs " << f[a][k];
          ++tested;
        }
    }
  }
  RecordProperty("worst_relative_error", std::to_string(worst));
  std::printf("[ measured ] element forces vs −∂W/∂u: %d components, worst relative error %.3g\n",
              tested, worst);
}

TEST(Muscle, CurvesAreContinuousAndIntegralsMatchQuadrature) {
  // fa: values at the joints and the peak.
  EXPECT_NEAR(blemker_active(0.6), 1 - 4 * 0.16, 1e-12);
  EXPECT_NEAR(blemker_active(1.0), 1.0, 1e-15);
  EXPECT_NEAR(blemker_active(1.4), 9 * 0.04, 1e-12);
  EXPECT_EQ(blemker_active(0.39), 0.0);
  EXPECT_EQ(blemker_active(1.61), 0.0);
  // fp: continuous value and slope at x*.
  const double p1 = 0.05, p2 = 6.6, xs = 1.4, d = 1e-7;
  EXPECT_NEAR(passive_fibre(xs - d, p1, p2, xs), passive_fibre(xs + d, p1, p2, xs), 1e-5);
  const double sl = (passive_fibre(xs + 2 * d, p1, p2, xs) - passive_fibre(xs + d, p1, p2, xs)) / d;
  const double sr = (passive_fibre(xs - d, p1, p2, xs) - passive_fibre(xs - 2 * d, p1, p2, xs)) / d;
  EXPECT_NEAR(sl, sr, 1e-4 * sl);
  EXPECT_NEAR(passive_fibre_max_slope(p1, p2, xs), sl, 1e-4 * sl);
  // Integrals against Simpson quadrature from 1.
  for (double x : {0.3, 0.45, 0.7, 0.95, 1.2, 1.45, 1.55, 1.7, 1.9}) {
    const int n = 20000;
    double sa = 0, sp = 0;
    const double hstep = (x - 1) / n;
    for (int i = 0; i <= n; ++i) {
      const double s = 1 + i * hstep;
      const double wgt = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
      sa += wgt * blemker_active(s);
      sp += wgt * passive_fibre(s, p1, p2, xs);
    }
    sa *= hstep / 3;
    sp *= hstep / 3;
    EXPECT_NEAR(blemker_active_integral(x), sa, 1e-6) << x;
    EXPECT_NEAR(passive_fibre_integral(x, p1, p2, xs), sp, 1e-6) << x;
  }
}

// The element's energies (physics::element_forces, what every backend sums): the elastic energy is
// the energy stored in the material, V0 (W_nH + Σ passive muscle); the strain energy adds the active
// muscle potential at the current activation, which is negative in a shortened, active fibre, so a
// contracting muscle's element can have strain < 0 < elastic. Against the separate laws.
TEST(ElementEnergies, ElasticIsTheStoredPartAndStrainAddsTheActivePotential) {
  const double h = 1e-3, v0 = h * h * h;
  const ElementRow<double> row{300.0, 300.0 * 2 * 1.49 / (3 * 0.02), 5.0};
  const MuscleParams<double> params[2] = {{5e4, 1.0, 0.05, 6.6, 1.4}, {2e4, 1.1, 0.1, 5.0, 1.5}};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> small(-0.01, 0.01);
  for (const double stretch : {0.85, 1.0, 1.25}) {
    for (const double activation : {0.0, 0.7}) {
      const V fibres[2] = {(1 / norm(V{1, 0.1, 0})) * V{1, 0.1, 0}, V{1, 0, 0}};
      const std::int32_t ids[2] = {0, 1};
      const double fractions[2] = {0.6, 0.3};
      const double activations[2] = {activation, 0.5 * activation};
      const MuscleEntries<double> muscles{ids, fractions, fibres, params, activations, 0, 2};
      V x[8], u[8];
      cube_nodes(h, x);
      for (int a = 0; a < 8; ++a)
        u[a] = V{x[a].x * (stretch - 1) + small(rng) * h, small(rng) * h, small(rng) * h};
      V fe[8];
      const auto out = element_forces<double, true, true, true, true>(u, h, row, muscles, fe);
      // Independently: the laws one by one.
      const Mat3d f = hex8_deformation_gradient(u, h);
      const double j = determinant(f);
      const SymMat3<double> cg = transpose_product(f);
      double stored = v0 * neo_hookean_energy(cg, j, row.mu, row.kappa), active = 0;
      for (int k = 0; k < 2; ++k) {
        stored += v0 * muscle_passive_energy(cg, fibres[k], fractions[k], params[k]);
        active += v0 * muscle_active_energy(cg, fibres[k], fractions[k], activations[k], params[k]);
        // The two parts are the whole muscle energy.
        EXPECT_NEAR(
            muscle_passive_energy(cg, fibres[k], fractions[k], params[k]) +
                muscle_active_energy(cg, fibres[k], fractions[k], activations[k], params[k]),
            muscle_energy(cg, fibres[k], fractions[k], activations[k], params[k]),
            1e-12 * params[k].reference_stress);
      }
      V dummy[8] = {};
      const double hourglass = add_hourglass_forces(u, row.hourglass_k, dummy, true);
      const double tol = 1e-12 * 5e4 * v0;
      EXPECT_NEAR(out.elastic, stored, tol) << stretch << " " << activation;
      EXPECT_NEAR(out.strain, stored + active, tol) << stretch << " " << activation;
      EXPECT_NEAR(out.hourglass, hourglass, 1e-12 * std::abs(hourglass) + 1e-30);
      EXPECT_GE(out.elastic, 0.0);
      if (activation == 0) {
        EXPECT_EQ(out.strain, out.elastic) << stretch;
      }
      if (stretch < 1 && activation > 0) {
        EXPECT_LT(out.strain, 0.0) << "a contracting muscle's potential outweighs its storage";
        EXPECT_GT(out.elastic, 0.0);
      }
    }
  }
}

TEST(Muscle, NominalStressConvention) {
  // P = F S along the fibre: with F = diag(λ, 1, 1) and a0 = e1, P11 = T.
  const MuscleParams<double> mp{5e6, 1.0, 0.05, 6.6, 1.4};
  const double lam = 1.1, a = 0.6;
  const Mat3d f = {{{lam, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  SymMat3<double> s = sym_zero<double>();
  const double t = add_muscle_stress(transpose_product(f), V{1, 0, 0}, 1.0, a, mp, s);
  const Mat3d p = f * s;
  EXPECT_NEAR(t, 5e6 * (a * blemker_active(1.1) + passive_fibre(1.1, 0.05, 6.6, 1.4)), 1e-6);
  EXPECT_NEAR(p(0, 0), t, 1e-6);
}

TEST(CentralDifference, CoefficientsMatchTheCentredForm) {
  const double dt = 1e-3, alpha = 5, m = 0.02;
  const auto cd = central_difference<double>(dt, alpha);
  const double a = 1 / (m / (dt * dt) + alpha * m / (2 * dt));
  const double b = 2 * m * a / (dt * dt);
  const double c = alpha * m * a / (2 * dt) - b / 2;
  EXPECT_NEAR(cd.a_over_inverse_mass / m, a, 1e-15 * a);
  EXPECT_NEAR(cd.b, b, 1e-14);
  EXPECT_NEAR(cd.c, c, 1e-14);
  // A free single degree of freedom decays by exactly damping_step_factor per step in modulus:
  // the product of the two roots of the recurrence is −Cc.
  EXPECT_NEAR(std::sqrt(-cd.c), damping_step_factor(dt, alpha), 1e-15);
}

TEST(Sliding, ClosestPointOnTriangleMatchesBruteForce) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const V a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)}, c{u(rng), u(rng), u(rng)};
    const V p{2 * u(rng), 2 * u(rng), 2 * u(rng)};
    const V q = closest_point_on_triangle(p, a, b, c);
    double best = 1e300;
    const int n = 300;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const double s = double(i) / n, t = double(j) / n;
        const V x = a + s * (b - a) + t * (c - a);
        best = std::min(best, norm(p - x));
      }
    EXPECT_LE(norm(p - q), best + 1e-12);
    EXPECT_GE(norm(p - q), best - 2.0 * 3 / n);
  }
  // Projection back to the rest distance, from either side.
  const V a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  const V n = triangle_normal(a, b, c);
  EXPECT_NEAR(n.z, 1.0, 1e-15);
  const V x1 = project_to_rest_distance(V{0.2, 0.2, 0.5}, V{0.2, 0.2, 0}, n, 0.1);
  EXPECT_NEAR(x1.z, 0.1, 1e-15);
  const V x2 = project_to_rest_distance(V{0.2, 0.2, -0.5}, V{0.2, 0.2, 0}, n, 0.1);
  EXPECT_NEAR(x2.z, 0.1, 1e-15);
  const V pl = project_to_plane(V{1, 2, 3}, V{0, 1, 0});
  EXPECT_EQ(pl.y, 0.0);
}

TEST(TimeStep, CourantEstimate) {
  // h / sqrt(M/ρ): μ = 1000, ν = 0.49, ρ = 1000, h = 1 mm.
  const double mu = 1000, kappa = 2 * mu * 1.49 / (3 * 0.02);
  const double m = p_wave_modulus(mu, kappa);
  EXPECT_NEAR(m, kappa + 4 * mu / 3, 1e-9);
  EXPECT_NEAR(critical_time_step(1e-3, m, 1000.0), 1e-3 / std::sqrt(m / 1000), 1e-15);
  EXPECT_GT(critical_time_step(1e-3, 0.0, 1000.0), 1e20);
}

}  // namespace
}  // namespace sinew::simulator::physics
