// The jaw (physics/jaw.hpp, Setup::jaw) on every backend built: its nodes follow the rigid motion
// of the curves to the bit (the host's map in the run's scalar, applied with the same rounded
// operations on the CPU and the GPU), the tissue between the jaw and the held end deforms without
// inverting, and the jaw's work is what the body stores (energy balance of central differences).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "engine_test_support.hpp"
#include "sinew/simulator/physics/jaw.hpp"

namespace sinew::simulator::testing {
namespace {

using SimSetup = sinew::simulator::Setup;
const std::vector<NamedBackend>& kBackends = every_backend();

class JawMotionTest : public BackendTest<std::tuple<NamedBackend, Precision>> {};

constexpr double kH = 1e-3;

// A block of 8 × 3 × 3 mm held at x = 0; its last two mm (lattice x ≥ 6) are the jaw, hinged about
// the line along y through (−2 mm, ·, 1.5 mm) and opened 6° over 20 ms, with a 1 mm protrusion
// (along x) and a 0.5 mm lateral shift (along y), held to 30 ms.
Setup jaw_setup(const formats::Model& m, Precision precision) {
  Setup s;
  s.precision = precision;
  s.duration = 0.03;
  s.rigid_nodes = nodes_at(m, 0, 0);
  JawMotion j;
  for (std::size_t n = 0; n < m.node_count(); ++n)
    if (m.node_lattice[n][0] >= 6) j.nodes.push_back(Index(n));
  j.pivot = {-2 * kH, 0, 1.5 * kH};
  j.axis = {0, 1, 0};
  j.forward = {1, 0, 0};
  j.incisal = {8 * kH, 1.5 * kH, 0};
  j.opening = Curve::ramp(0.02, 6 * std::numbers::pi / 180);
  j.protrusion = Curve::ramp(0.02, 1e-3);
  j.lateral = Curve::ramp(0.02, 0.5e-3);
  s.jaw = j;
  return s;
}

template <typename T>
void expect_jaw_nodes_exact(const formats::Model& m, const Setup& s, Backend& b) {
  // u(k) comes from the step k − 1 → k, whose map is the jaw's at t_(k−1) + Δt (step_scalars).
  const std::int64_t k = b.step_index();
  const double t = double(k - 1) * b.dt() + b.dt();
  const JawMotion& j = *s.jaw;
  double map[physics::kJawMapSize];
  j.map(t, map);
  T typed[physics::kJawMapSize];
  for (int q = 0; q < physics::kJawMapSize; ++q) typed[q] = T(map[q]);
  const auto u = b.displacements();
  for (const Index nd : j.nodes) {
    const auto x = m.node_position(nd);
    const Vec3<T> expected = physics::jaw_displacement(typed, Vec3<T>{T(x[0]), T(x[1]), T(x[2])});
    for (int c = 0; c < 3; ++c)
      ASSERT_EQ(u[3 * std::size_t(nd) + std::size_t(c)], double(expected[c]))
          << "node " << nd << " component " << c << " at step " << k;
  }
}

TEST_P(JawMotionTest, NodesFollowTheCurvesToTheBitAndTheWorkIsStored) {
  const auto& [backend, precision] = GetParam();
  const auto model = block(8, 3, 3, kH, neo_hookean(1000, 0.45, 1000));
  const SimSetup s = jaw_setup(model, precision);
  auto b = backend.make(model, s);
  const std::int64_t steps = b->plan().steps;
  ASSERT_GT(steps, 100);
  b->step(steps / 2);
  if (precision == Precision::float32)
    expect_jaw_nodes_exact<float>(model, s, *b);
  else
    expect_jaw_nodes_exact<double>(model, s, *b);
  b->step(steps - steps / 2);  // throws InstabilityError on an inverted element
  if (precision == Precision::float32)
    expect_jaw_nodes_exact<float>(model, s, *b);
  else
    expect_jaw_nodes_exact<double>(model, s, *b);
  const auto e = b->energies();
  ASSERT_GT(e.external_work, 0);
  const double stored = e.strain + e.hourglass + e.kinetic;
  EXPECT_NEAR(stored, e.external_work, 0.05 * e.external_work)
      << "strain " << e.strain << " hourglass " << e.hourglass << " kinetic " << e.kinetic;
}

TEST(JawMotion, TheMapIsARigidMotionAboutThePivot) {
  // Rodrigues against the rotation about y written out: x' = R(θ)(x − p) + p + d.
  const double pivot[3] = {0.01, -0.02, 0.03}, axis[3] = {0, 1, 0}, forward[3] = {0, 0, 1};
  const physics::JawPose pose{0.3, 2e-3, -1e-3};
  double map[physics::kJawMapSize];
  physics::jaw_displacement_map(pivot, axis, forward, pose, map);
  const double c = std::cos(0.3), sn = std::sin(0.3);
  const double x[3] = {0.05, 0.04, -0.02};
  const double r[3] = {x[0] - pivot[0], x[1] - pivot[1], x[2] - pivot[2]};
  // Rotation about +y: (x, z) → (x cos θ + z sin θ, −x sin θ + z cos θ).
  const double moved[3] = {c * r[0] + sn * r[2] + pivot[0] - x[0], r[1] + pivot[1] - x[1] - 1e-3,
                           -sn * r[0] + c * r[2] + pivot[2] - x[2] + 2e-3};
  const auto u = physics::jaw_displacement(map, Vec3<double>{x[0], x[1], x[2]});
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(u[k], moved[k], 1e-15) << k;
  // Distances between carried points are kept.
  const Vec3<double> a{0.05, 0.04, -0.02}, b2{-0.03, 0.01, 0.07};
  const auto ua = physics::jaw_displacement(map, a), ub = physics::jaw_displacement(map, b2);
  const double before = std::hypot(a[0] - b2[0], a[1] - b2[1], a[2] - b2[2]);
  const double after = std::hypot(a[0] + ua[0] - b2[0] - ub[0], a[1] + ua[1] - b2[1] - ub[1],
                                  a[2] + ua[2] - b2[2] - ub[2]);
  EXPECT_NEAR(after, before, 1e-15);
}

std::string jaw_case_name(const ::testing::TestParamInfo<std::tuple<NamedBackend, Precision>>& i) {
  return std::get<0>(i.param).name +
         (std::get<1>(i.param) == Precision::float32 ? "_float" : "_double");
}

INSTANTIATE_TEST_SUITE_P(Backends, JawMotionTest,
                         ::testing::Combine(::testing::ValuesIn(kBackends),
                                            ::testing::Values(Precision::float32,
                                                              Precision::float64)),
                         jaw_case_name);

}  // namespace
}  // namespace sinew::simulator::testing
