// Verification of the engine against closed forms (physics-notes §7, μ = 1000 Pa), run on every
// backend in kBackends through the BackendFactory. Static answers by dynamic relaxation on small
// blocks; the kinetic energy left is checked to be negligible.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <ostream>
#include <random>

#include "engine_test_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/simulator/physics/muscle.hpp"
#ifdef SINEW_CUDA_ENABLED
#include "sinew/simulator/engine/cuda_backend.hpp"
#endif

namespace sinew::simulator::testing {
using SimSetup = sinew::simulator::Setup;
namespace {

const std::vector<NamedBackend>& kBackends = every_backend();

class Verification : public BackendTest<NamedBackend> {
 protected:
  std::unique_ptr<Backend> make(const formats::Model& m, const SimSetup& s) {
    return GetParam().make(m, s);
  }
};

constexpr double kMu = 1000;
constexpr double kRho = 1000;
constexpr double kH = 1e-3;

double rel(double a, double b) {
  return std::abs(a - b) / std::abs(b);
}

// One prescribed set per node: u = value.
void prescribe_node(SimSetup& s, Index n, std::array<double, 3> value, Curve curve = {}) {
  PrescribedDisplacement p;
  p.nodes = {n};
  p.value = value;
  p.curve = std::move(curve);
  s.prescribed.push_back(std::move(p));
}

std::array<double, 3> rest(const formats::Model& m, Index n) {
  return m.node_position(n);
}

// ---- patch test --------------------------------------------------------------------------------
TEST_P(Verification, PatchTestReproducesAHomogeneousDeformationToRoundOff) {
  const int n = 3;
  const auto mat = neo_hookean(kMu, 0.45, kRho);
  const auto model = block(n, n, n, kH, mat);
  const double g[3][3] = {{0.10, 0.05, 0.0}, {0.0, -0.05, 0.02}, {0.03, 0.0, 0.08}};
  auto exact = [&](Index node) {
    const auto x = rest(model, node);
    std::array<double, 3> u{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) u[std::size_t(i)] += g[i][j] * x[std::size_t(j)];
    return u;
  };
  SimSetup s = static_setup(critical_alpha(kMu, kRho, n * kH));
  for (std::size_t i = 0; i < model.node_count(); ++i) {
    const auto& l = model.node_lattice[i];
    const bool boundary =
        l[0] == 0 || l[0] == n || l[1] == 0 || l[1] == n || l[2] == 0 || l[2] == n;
    if (boundary) prescribe_node(s, Index(i), exact(Index(i)));
  }
  auto b = make(model, s);
  double err = 1e300;
  for (int it = 0; it < 200 && err > 2e-13 * 0.1 * n * kH; ++it) {
    b->step(200);
    const auto u = b->displacements();
    err = 0;
    for (std::size_t i = 0; i < model.node_count(); ++i) {
      const auto e = exact(Index(i));
      for (int k = 0; k < 3; ++k)
        err = std::max(err, std::abs(u[3 * i + std::size_t(k)] - e[std::size_t(k)]));
    }
  }
  const double scale = 0.1 * n * kH;  // largest displacement
  EXPECT_LT(err / scale, 1e-12);
  const auto en = b->energies();
  EXPECT_LT(en.hourglass, 1e-20 * en.strain + 1e-30);
  // Every element: the closed-form Cauchy stress.
  const auto fields = b->element_fields();
  const double f[3][3] = {{1 + g[0][0], g[0][1], g[0][2]},
                          {g[1][0], 1 + g[1][1], g[1][2]},
                          {g[2][0], g[2][1], 1 + g[2][2]}};
  double bm[3][3] = {}, j = 0;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) bm[i][k] += f[i][l] * f[k][l];
  j = f[0][0] * (f[1][1] * f[2][2] - f[1][2] * f[2][1]) -
      f[0][1] * (f[1][0] * f[2][2] - f[1][2] * f[2][0]) +
      f[0][2] * (f[1][0] * f[2][1] - f[1][1] * f[2][0]);
  const double kappa = mat.bulk_modulus;
  const double i1 = bm[0][0] + bm[1][1] + bm[2][2];
  // σ = μ J^(−5/3) (b − I1/3 I) + κ (J − 1) I
  const int vi[6][2] = {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}};
  double worst = 0;
  for (std::size_t e = 0; e < model.element_count(); ++e) {
    EXPECT_NEAR(fields.jacobian[e], j, 1e-12);
    for (int k = 0; k < 6; ++k) {
      const int a = vi[k][0], c = vi[k][1];
      const double sig = kMu * std::pow(j, -5.0 / 3) * (bm[a][c] - (a == c ? i1 / 3 : 0)) +
                         (a == c ? kappa * (j - 1) : 0);
      worst = std::max(worst, std::abs(fields.cauchy[e][std::size_t(k)] - sig) / 1e4);
    }
  }
  EXPECT_LT(worst, 1e-9);
  std::printf(
      "[ measured ] patch: max |u − (F−I)X| / |u|max = %.3g, stress error / 1e4 Pa = %.3g, "
      "hourglass energy %.3g J (strain %.3g J)\n",
      err / scale, worst, en.hourglass, en.strain);
}

// ---- uniaxial ----------------------------------------------------------------------------------
TEST_P(Verification, UniaxialStretchMatchesClosedForm) {
  const int n = 2;
  const double l = n * kH;
  const auto model = block(n, n, n, kH, neo_hookean(kMu, 0.49, kRho));
  SimSetup s = static_setup(2 * critical_alpha(kMu, kRho, l));
  PrescribedDisplacement pull;
  pull.nodes = nodes_at(model, 0, n);
  pull.components = {true, false, false};
  pull.value = {0.5 * l, 0, 0};
  pull.curve = Curve::ramp(0.05, 1.0);
  s.prescribed.push_back(pull);
  s.sliding_planes.push_back({nodes_at(model, 0, 0), {1, 0, 0}});
  s.sliding_planes.push_back({nodes_at(model, 1, 0), {0, 1, 0}});
  s.sliding_planes.push_back({nodes_at(model, 2, 0), {0, 0, 1}});
  auto b = make(model, s);
  b->step(std::int64_t(std::ceil(0.05 / b->dt())));
  const double ke = relax(*b, 20000, 1e-22);
  const auto u = b->displacements();
  const auto top = nodes_at(model, 1, n);
  double lateral = 0;
  for (auto nd : top) lateral += 1 + node_u(u, nd)[1] / l;
  lateral /= double(top.size());
  const double p11 = b->reaction(pull.nodes)[0] / (l * l);
  const auto en = b->energies();
  EXPECT_NEAR(lateral, 0.820731, 0.820731 * 1e-5);
  EXPECT_LT(rel(p11, 1043.71), 1e-3);
  EXPECT_LT(ke, 1e-10 * en.strain);
  std::printf(
      "[ measured ] uniaxial 1.5, ν = 0.49: lateral stretch %.7f (0.820731), P11 = %.4f Pa "
      "(1043.71), KE/strain %.2g, hourglass/strain %.2g\n",
      lateral, p11, ke / en.strain, en.hourglass / en.strain);
}

// ---- confined compression ----------------------------------------------------------------------
class Confined : public BackendTest<std::tuple<NamedBackend, double>> {};

TEST_P(Confined, ConfinedCompressionMatchesClosedForm) {
  const auto& [backend, nu] = GetParam();
  const double expected = nu < 0.495 ? -10281.45 : -100281.45;  // notes §7
  const int n = 2;
  const double l = n * kH;
  const auto model = block(n, n, n, kH, neo_hookean(kMu, nu, kRho));
  SimSetup s = static_setup(0);
  s.effects.damping = true;
  // Lateral displacements zero everywhere; x fixed at x = 0, x = −0.2 L at x = L.
  PrescribedDisplacement lateral;
  for (std::size_t i = 0; i < model.node_count(); ++i) lateral.nodes.push_back(Index(i));
  lateral.components = {false, true, true};
  s.prescribed.push_back(lateral);
  PrescribedDisplacement left{nodes_at(model, 0, 0), {true, false, false}, {0, 0, 0}, {}};
  s.prescribed.push_back(left);
  PrescribedDisplacement push{
      nodes_at(model, 0, n), {true, false, false}, {-0.2 * l, 0, 0}, Curve::ramp(0.01, 1.0)};
  s.prescribed.push_back(push);
  const double cd = std::sqrt((model.materials[0].bulk_modulus + 4 * kMu / 3) / kRho);
  s.damping_alpha = 2 * M_PI * cd / l;  // ≈ critical for the 1-D dilatational mode
  auto b = backend.make(model, s);
  b->step(std::int64_t(std::ceil(0.01 / b->dt())));
  const double ke = relax(*b, 20000, 1e-24);
  const double p11 = b->reaction(push.nodes)[0] / (l * l);
  const auto en = b->energies();
  EXPECT_LT(rel(p11, expected), 1e-3);
  EXPECT_LT(ke, 1e-10 * en.strain);
  std::printf("[ measured ] confined 0.8, ν = %.3f: P11 = %.3f Pa (%.2f), rel. error %.2g\n", nu,
              p11, expected, rel(p11, expected));
}

// ---- simple shear ------------------------------------------------------------------------------
TEST_P(Verification, SimpleShearMatchesClosedForm) {
  const int n = 3;
  const auto model = block(n, n, n, kH, neo_hookean(kMu, 0.49, kRho));
  SimSetup s = static_setup(critical_alpha(kMu, kRho, n * kH));
  const double ramp = 0.04;
  for (std::size_t i = 0; i < model.node_count(); ++i) {
    const auto& lt = model.node_lattice[i];
    const bool boundary =
        lt[0] == 0 || lt[0] == n || lt[1] == 0 || lt[1] == n || lt[2] == 0 || lt[2] == n;
    if (boundary)
      prescribe_node(s, Index(i), {rest(model, Index(i))[1], 0, 0}, Curve::ramp(ramp, 1.0));
  }
  auto b = make(model, s);
  b->step(std::int64_t(std::ceil(ramp / b->dt())));
  const double ke = relax(*b, 40000, 1e-24);
  const auto f = b->element_fields();
  double w12 = 0, w11 = 0, w22 = 0, w33 = 0;
  for (std::size_t e = 0; e < model.element_count(); ++e) {
    w12 = std::max(w12, rel(f.cauchy[e][5], 1000.0));
    w11 = std::max(w11, rel(f.cauchy[e][0], 2000.0 / 3));
    w22 = std::max(w22, rel(f.cauchy[e][1], -1000.0 / 3));
    w33 = std::max(w33, rel(f.cauchy[e][2], -1000.0 / 3));
  }
  EXPECT_LT(w12, 1e-3);
  EXPECT_LT(w11, 1e-3);
  EXPECT_LT(w22, 1e-3);
  EXPECT_LT(w33, 1e-3);
  EXPECT_LT(ke, 1e-10 * b->energies().strain);
  std::printf(
      "[ measured ] simple shear γ = 1: element 0 σ12 = %.3f, σ11 = %.3f, σ22 = %.3f, σ33 = "
      "%.3f Pa; worst rel. errors %.2g %.2g %.2g %.2g\n",
      f.cauchy[0][5], f.cauchy[0][0], f.cauchy[0][1], f.cauchy[0][2], w12, w11, w22, w33);
}

// ---- damping envelope --------------------------------------------------------------------------
TEST_P(Verification, DampingEnvelopeDecaysAsExpMinusAlphaTOverTwo) {
  // One cube, bottom nodes rigid, top nodes free along x only: a single shear mode.
  const double rho = 1e7;  // slow mode (period ≈ 0.44 s)
  const auto model = block(1, 1, 1, kH, neo_hookean(kMu, 0.3, rho));
  SimSetup s;
  s.effects.damping = true;
  s.damping_alpha = 5;
  s.rigid_nodes = nodes_at(model, 2, 0);
  const auto top = nodes_at(model, 2, 1);
  s.sliding_planes.push_back({top, {0, 1, 0}});
  s.sliding_planes.push_back({top, {0, 0, 1}});
  s.initial_velocities.push_back({top, {1e-6, 0, 0}});
  s.time_step.policy = TimeStepPolicy::user;
  s.time_step.user_dt = 5e-4;
  auto b = make(model, s);
  std::vector<double> x;
  const int steps = 5000;
  for (int i = 0; i < steps; ++i) {
    x.push_back(b->displacements()[3 * std::size_t(top[0])]);
    b->step(1);
  }
  // Positive peaks, refined by a parabola through three samples.
  std::vector<std::pair<double, double>> peaks;
  for (int i = 1; i + 1 < steps; ++i) {
    if (x[std::size_t(i)] > x[std::size_t(i - 1)] && x[std::size_t(i)] >= x[std::size_t(i + 1)] &&
        x[std::size_t(i)] > 0) {
      const double ym = x[std::size_t(i - 1)], y0 = x[std::size_t(i)], yp = x[std::size_t(i + 1)];
      const double d = 0.5 * (ym - yp) / (ym - 2 * y0 + yp);
      peaks.push_back({(i + d) * b->dt(), y0 - 0.25 * (ym - yp) * d});
    }
  }
  ASSERT_GE(peaks.size(), 4u);
  double worst = 0;
  for (std::size_t k = 1; k < peaks.size(); ++k) {
    const double expected = peaks[0].second * std::exp(-2.5 * (peaks[k].first - peaks[0].first));
    worst = std::max(worst, rel(peaks[k].second, expected));
  }
  EXPECT_LT(worst, 1e-3);
  std::printf(
      "[ measured ] damping α = 5/s: %zu peaks over %.2f s, amplitude %.3g → %.3g, worst "
      "deviation from exp(−2.5 t) %.2g\n",
      peaks.size(), peaks.back().first - peaks.front().first, peaks.front().second,
      peaks.back().second, worst);
}

// ---- stability ---------------------------------------------------------------------------------
SimSetup free_block_setup(const formats::Model& model, double factor) {
  SimSetup s;
  s.time_step.policy = TimeStepPolicy::forced;
  const double cd = std::sqrt((model.materials[0].bulk_modulus + 4 * kMu / 3) / kRho);
  s.time_step.user_dt = factor * kH / cd;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> v(-1e-4, 1e-4);
  for (std::size_t i = 0; i < model.node_count(); ++i)
    s.initial_velocities.push_back({{Index(i)}, {v(rng), v(rng), v(rng)}});
  return s;
}

TEST_P(Verification, StableAtPointEightOfHOverCd) {
  const auto model = block(8, 8, 8, kH, neo_hookean(kMu, 0.49, kRho));
  auto b = make(model, free_block_setup(model, 0.8));
  const auto e0 = b->energies();
  // Central differences conserve a shadow energy, not KE(n−½) + U(n) exactly; at 0.8 of the limit
  // the high modes make that sum wander by some 10%. An unstable mode would grow it by orders of
  // magnitude within tens of steps.
  const double total0 = e0.kinetic + e0.strain + e0.hourglass;
  double total_max = 0;
  for (int i = 0; i < 40; ++i) {
    ASSERT_NO_THROW(b->step(100));
    const auto e = b->energies();
    total_max = std::max(total_max, e.kinetic + e.strain + e.hourglass);
  }
  EXPECT_LT(total_max, 1.5 * total0);
  std::printf(
      "[ measured ] stability 0.8 h/c_d, 4000 steps: energy %.4g J initially, at most %.4g J "
      "(ratio %.3f)\n",
      total0, total_max, total_max / total0);
}

TEST_P(Verification, InstabilityAtOneHOverCdIsDetectedAndReported) {
  const auto model = block(8, 8, 8, kH, neo_hookean(kMu, 0.49, kRho));
  auto b = make(model, free_block_setup(model, 1.0));
  std::string message;
  std::int64_t at = -1;
  try {
    b->step(5000);
  } catch (const InstabilityError& e) {
    message = e.what();
    at = b->step_index();
  }
  ASSERT_FALSE(message.empty()) << "no instability detected in 5000 steps at 1.0 h/c_d";
  EXPECT_NE(message.find("step"), std::string::npos);
  EXPECT_NE(message.find("position"), std::string::npos);
  // The state stays readable and finite (the last good step).
  for (double v : b->displacements()) ASSERT_TRUE(std::isfinite(v));
  std::printf("[ measured ] stability 1.0 h/c_d: detected at step %lld: %s\n", (long long)at,
              message.c_str());
}

TEST_P(Verification, InvertedElementIsDetectedAndReported) {
  // One cube crushed through itself: bottom rigid, top pushed down by 1.5 h over 0.1 s.
  const auto model = block(1, 1, 1, kH, neo_hookean(kMu, 0.3, kRho));
  SimSetup s;
  s.effects.loads = true;
  s.rigid_nodes = nodes_at(model, 2, 0);
  s.prescribed.push_back(
      {nodes_at(model, 2, 1), {true, true, true}, {0, 0, -1.5 * kH}, Curve::ramp(0.1, 1.0)});
  auto b = make(model, s);
  std::string message;
  try {
    b->step(std::int64_t(std::ceil(0.1 / b->dt())) + 10);
  } catch (const InstabilityError& e) {
    message = e.what();
  }
  ASSERT_NE(message.find("inverted element (J ≤ 0)"), std::string::npos) << message;
  EXPECT_NE(message.find("element 0"), std::string::npos);
  // J crosses zero when the top has moved down by h: at t = 0.1 s / 1.5.
  EXPECT_NEAR(b->time(), 0.1 / 1.5, 2 * b->dt());
  for (double v : b->displacements()) ASSERT_TRUE(std::isfinite(v));
  std::printf("[ measured ] inversion: %s\n", message.c_str());
}

// ---- isometric muscle --------------------------------------------------------------------------
struct MuscleCase {
  double stretch, activation, p1;
};
void PrintTo(const MuscleCase& c, std::ostream* os) {
  *os << "stretch " << c.stretch << ", activation " << c.activation << ", p1 " << c.p1;
}
class IsometricMuscle : public BackendTest<std::tuple<NamedBackend, MuscleCase>> {};

TEST_P(IsometricMuscle, EndForceIsReferenceStressTimesCurvesTimesArea) {
  const auto& [backend, c] = GetParam();
  formats::BoxSpec spec;
  spec.dims = {3, 2, 2};
  spec.voxel_size = kH;
  spec.materials = {neo_hookean(kMu, 0.49, kRho)};
  formats::BoxMuscleSpec m;
  m.element_min = {0, 0, 0};
  m.element_max = {3, 2, 2};
  m.fibre = {1, 0, 0};
  m.passive_p1 = c.p1;
  spec.muscles = {m};
  spec.created = "2026-01-01T00:00:00Z";
  const auto model = formats::make_box_model(spec);
  const double l = 3 * kH, a0 = 4 * kH * kH;
  SimSetup s;
  s.effects.elasticity = false;  // no matrix: the fibres alone
  s.effects.hourglass = false;
  s.effects.muscles = true;
  s.effects.loads = true;
  s.effects.damping = true;
  s.activation = {Curve::constant(c.activation)};
  const auto end = nodes_at(model, 0, 3);
  s.prescribed.push_back({end, {true, false, false}, {(c.stretch - 1) * l, 0, 0}, {}});
  s.sliding_planes.push_back({nodes_at(model, 0, 0), {1, 0, 0}});
  s.sliding_planes.push_back({nodes_at(model, 1, 0), {0, 1, 0}});
  s.sliding_planes.push_back({nodes_at(model, 2, 0), {0, 0, 1}});
  // Fibre wave speed sqrt(σref f'/ρ); damp the 1-D mode near critically.
  s.damping_alpha = 2 * M_PI * std::sqrt(5e6 * 1.0 / kRho) / (2 * l);
  auto b = backend.make(model, s);
  relax(*b, 40000, 1e-20);
  const double force = b->reaction(end)[0];
  const double x = c.stretch;
  const double expected =
      5e6 *
      (c.activation * physics::blemker_active(x) + physics::passive_fibre(x, c.p1, 6.6, 1.4)) * a0;
  EXPECT_LT(rel(force, expected), 5e-3);
  const auto u = b->displacements();
  const auto mid = nodes_at(model, 0, 1);
  EXPECT_NEAR(node_u(u, mid[0])[0] / kH, c.stretch - 1, 1e-4);
  // Energies of the homogeneous fibres (volume l · a0, no matrix): the elastic energy is what the
  // tissue stores, the passive fibre energy σref V ∫_1^λ fp; the strain energy adds the active
  // potential σref V a ∫_1^λ fa, negative while the fibres are shorter than λopt = 1.
  const Energies e = b->energies();
  const double scale = 5e6 * l * a0;  // σref V, J
  const double passive = scale * physics::passive_fibre_integral(x, c.p1, 6.6, 1.4);
  const double active = scale * c.activation * physics::blemker_active_integral(x);
  EXPECT_NEAR(e.elastic, passive, 5e-3 * std::abs(passive) + 1e-12 * scale);
  EXPECT_NEAR(e.strain - e.elastic, active, 5e-3 * std::abs(active) + 1e-12 * scale);
  EXPECT_GE(e.elastic, 0.0);
  if (c.stretch < 1 && c.activation > 0) {
    EXPECT_LT(e.strain, 0.0);
  }
  std::printf(
      "[ measured ] isometric muscle λ0 = %.2f, a = %.2f, P1 = %.2f: end force %.6g N "
      "(expected %.6g N), rel. error %.2g; elastic %.6g J (expected %.6g J), strain %.6g J "
      "(expected %.6g J)\n",
      c.stretch, c.activation, c.p1, force, expected, rel(force, expected), e.elastic, passive,
      e.strain, passive + active);
}

// ---- gravity -----------------------------------------------------------------------------------
TEST_P(Verification, GravityIsCarriedByTheSupportsAndMassScalingAddsNoWeight) {
  const auto model = block(3, 3, 3, kH, neo_hookean(kMu, 0.45, kRho));
  SimSetup s;
  s.effects.gravity = true;
  s.effects.damping = true;
  s.mass_scaling = 4;
  s.damping_alpha = critical_alpha(kMu, 4 * kRho, 3 * kH);
  s.rigid_nodes = nodes_at(model, 2, 0);
  auto b = make(model, s);
  const double ke = relax(*b, 40000, 1e-30);
  const auto r = b->reaction(s.rigid_nodes);
  const double weight = kRho * 27 * kH * kH * kH * 9.81;
  EXPECT_LT(rel(r[2], weight), 1e-6);
  EXPECT_LT(std::abs(r[0]) + std::abs(r[1]), 1e-9 * weight);
  EXPECT_LT(ke, 1e-10 * b->energies().strain);
  std::printf(
      "[ measured ] gravity, mass scaling 4: support reaction %.9g N, weight %.9g N (rel %.2g)\n",
      r[2], weight, rel(r[2], weight));
}

// ---- bending and the hourglass modulus (notes §3) --------------------------------------------
// Cantilever 20 × 2 × 2 cubes, clamped at x = 0, a small tip load spread over the end face
// (nodal forces). Reference: Euler–Bernoulli P L³/(3EI) plus Timoshenko shear P L/(κ_s μ A),
// κ_s = 5/6. With two elements through the thickness, one-point hexahedra bend through their
// hourglass modes, so the hourglass modulus decides the answer.
double cantilever_ratio(const BackendFactory& make, double nu, HourglassModulus modulus) {
  const Cantilever c = make_cantilever(kMu, nu, kRho, kH, modulus);
  auto b = make(c.model, c.setup);
  double prev = 0, tip = 0;
  for (int it = 0; it < 1000; ++it) {
    b->step(500);
    tip = mean_drop(*b, c.tip_nodes);
    if (std::abs(tip - prev) < 1e-7 * std::abs(tip)) break;
    prev = tip;
  }
  return tip / c.reference;
}

TEST_P(Verification, BendingDoesNotLockAsNuApproachesOneHalf) {
  const double r03 = cantilever_ratio(GetParam().make, 0.3, HourglassModulus::shear);
  const double r049 = cantilever_ratio(GetParam().make, 0.49, HourglassModulus::shear);
  const double r0499 = cantilever_ratio(GetParam().make, 0.499, HourglassModulus::shear);
  const double p049 = cantilever_ratio(GetParam().make, 0.49, HourglassModulus::p_wave);
  for (double r : {r03, r049, r0499}) {
    EXPECT_GT(r, 0.9);
    EXPECT_LT(r, 1.15);
  }
  EXPECT_LT(std::abs(r0499 - r03) / r03, 0.03);
  EXPECT_LT(p049, 0.5);  // the trap: M* = λ + 2μ locks bending
  std::printf(
      "[ measured ] cantilever 20×2×2 tip / beam theory: shear M* = 2μ: ν 0.3 %.3f, 0.49 "
      "%.3f, 0.499 %.3f; p-wave M* = λ+2μ at ν 0.49: %.3f\n",
      r03, r049, r0499, p049);
}

// ---- rigid rotation ----------------------------------------------------------------------------
TEST_P(Verification, RigidRotationOfAPrestretchedBlockKeepsEnergyAndRotatesReactions) {
  formats::BoxSpec spec;
  spec.dims = {3, 3, 3};
  spec.voxel_size = kH;
  spec.materials = {neo_hookean(kMu, 0.45, kRho), neo_hookean(3 * kMu, 0.4, kRho, "stiff")};
  spec.layer_boundaries = {1.4 * kH};  // a cut layer: multi-material elements
  formats::BoxMuscleSpec m;
  m.element_min = {0, 0, 1};
  m.element_max = {3, 3, 3};
  m.fibre = {1, 0.3, 0.2};
  m.reference_stress = 2e4;
  spec.muscles = {m};
  spec.created = "2026-01-01T00:00:00Z";
  const auto model = formats::make_box_model(spec);
  // Pre-stretch: a homogeneous F plus a random perturbation.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> p(-0.03 * kH, 0.03 * kH);
  std::vector<std::array<double, 3>> u0(model.node_count());
  const double fdiag[3] = {1.2, 0.9, 1.05};
  for (std::size_t i = 0; i < model.node_count(); ++i) {
    const auto x = rest(model, Index(i));
    for (int k = 0; k < 3; ++k) u0[i][std::size_t(k)] = (fdiag[k] - 1) * x[std::size_t(k)] + p(rng);
  }
  // R: rotation by 0.7 rad about (1, 2, 3)/|..|.
  const double ax[3] = {1 / std::sqrt(14.0), 2 / std::sqrt(14.0), 3 / std::sqrt(14.0)}, th = 0.7;
  double r[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double eps = (i == j) ? 1 : 0;
      double cross = 0;
      const int k = 3 - i - j;
      if (i != j) cross = ((j == (i + 1) % 3) ? -1 : 1) * ax[k];
      r[i][j] = std::cos(th) * eps + std::sin(th) * cross + (1 - std::cos(th)) * ax[i] * ax[j];
    }
  auto run = [&](bool rotate) {
    SimSetup s;
    s.effects.loads = true;
    s.effects.muscles = true;
    s.activation = {Curve::constant(0.5)};
    for (std::size_t i = 0; i < model.node_count(); ++i) {
      const auto x = rest(model, Index(i));
      std::array<double, 3> v = u0[i];
      if (rotate) {
        const double y[3] = {x[0] + v[0], x[1] + v[1], x[2] + v[2]};
        for (int a = 0; a < 3; ++a)
          v[std::size_t(a)] = r[a][0] * y[0] + r[a][1] * y[1] + r[a][2] * y[2] - x[std::size_t(a)];
      }
      prescribe_node(s, Index(i), v);
    }
    return make(model, s);
  };
  auto b0 = run(false), b1 = run(true);
  const auto e0 = b0->energies(), e1 = b1->energies();
  EXPECT_LT(rel(e1.strain, e0.strain), 1e-10);
  EXPECT_LT(rel(e1.hourglass, e0.hourglass), 1e-9);
  EXPECT_GT(e0.hourglass, 0.0);
  const auto face = nodes_at(model, 0, 3);
  const auto r0 = b0->reaction(face), r1 = b1->reaction(face);
  double err = 0;
  for (int a = 0; a < 3; ++a) {
    const double rr = r[a][0] * r0[0] + r[a][1] * r0[1] + r[a][2] * r0[2];
    err = std::max(err, std::abs(r1[std::size_t(a)] - rr));
  }
  const double mag = std::sqrt(r0[0] * r0[0] + r0[1] * r0[1] + r0[2] * r0[2]);
  EXPECT_LT(err / mag, 1e-10);
  // Every nodal force rotates.
  const auto f0 = b0->internal_forces(), f1 = b1->internal_forces();
  double ferr = 0, fmax = 0;
  for (std::size_t i = 0; i < model.node_count(); ++i)
    for (int a = 0; a < 3; ++a) {
      const double rr = r[a][0] * f0[3 * i] + r[a][1] * f0[3 * i + 1] + r[a][2] * f0[3 * i + 2];
      ferr = std::max(ferr, std::abs(f1[3 * i + std::size_t(a)] - rr));
      fmax = std::max(fmax, std::abs(f0[3 * i + std::size_t(a)]));
    }
  EXPECT_LT(ferr / fmax, 1e-10);
  std::printf(
      "[ measured ] rigid rotation: strain energy %.10g vs %.10g J (rel %.2g), hourglass "
      "rel %.2g, reaction rel err %.2g, nodal forces rel err %.2g\n",
      e0.strain, e1.strain, rel(e1.strain, e0.strain), rel(e1.hourglass, e0.hourglass), err / mag,
      ferr / fmax);
}

INSTANTIATE_TEST_SUITE_P(Backends, Verification, ::testing::ValuesIn(kBackends), backend_name);
INSTANTIATE_TEST_SUITE_P(Backends, Confined,
                         ::testing::Combine(::testing::ValuesIn(kBackends),
                                            ::testing::Values(0.49, 0.499)),
                         [](const auto& info) {
                           return std::get<0>(info.param).name +
                                  (std::get<1>(info.param) < 0.495 ? "_nu049" : "_nu0499");
                         });
INSTANTIATE_TEST_SUITE_P(Backends, IsometricMuscle,
                         ::testing::Combine(::testing::ValuesIn(kBackends),
                                            ::testing::Values(MuscleCase{0.9, 1.0, 0.0},
                                                              MuscleCase{0.8, 0.6, 0.05},
                                                              MuscleCase{1.2, 0.0, 0.05})),
                         [](const auto& info) {
                           const auto& c = std::get<1>(info.param);
                           return std::get<0>(info.param).name + "_stretch" +
                                  std::to_string(int(c.stretch * 100)) + "_a" +
                                  std::to_string(int(c.activation * 100));
                         });

}  // namespace
}  // namespace sinew::simulator::testing
