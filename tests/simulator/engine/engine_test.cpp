// Engine behaviour beyond the closed forms: sliding over a sphere, float vs double, bit-identical
// results for any thread count, checkpoint/restore, run on every backend in kBackends.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>

#include "engine_test_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/simulator/engine/backend_core.hpp"
#include "sinew/simulator/engine/cpu_engine.hpp"
#include "sinew/simulator/physics/sliding.hpp"
#include "test_meshes.hpp"

namespace sinew::simulator::testing {
namespace {
using SimSetup = sinew::simulator::Setup;

const NamedBackend kBackends[] = {{"cpu", &make_cpu_backend}};

class EngineTest : public ::testing::TestWithParam<NamedBackend> {};

// An icosphere of radius r about c as a sliding surface.
formats::Surface sphere(double r, std::array<double, 3> c, int levels) {
  const TriangleSoup m = make_icosphere(levels, r, c);
  formats::Surface s;
  s.name = "sphere";
  s.role = formats::SurfaceRole::sliding;
  s.vertices = m.vertices;
  s.triangles = m.triangles;
  return s;
}

// Brute-force distance of a point to a surface and the closest triangle.
std::pair<double, int> surface_distance(const formats::Surface& s, std::array<double, 3> x) {
  using V = Vec3<double>;
  double best = 1e300;
  int bt = -1;
  const V p{x[0], x[1], x[2]};
  for (std::size_t t = 0; t < s.triangles.size(); ++t) {
    const auto& a = s.vertices[std::size_t(s.triangles[t][0])];
    const auto& b = s.vertices[std::size_t(s.triangles[t][1])];
    const auto& c = s.vertices[std::size_t(s.triangles[t][2])];
    const V q = physics::closest_point_on_triangle(p, V{a[0], a[1], a[2]}, V{b[0], b[1], b[2]},
                                                   V{c[0], c[1], c[2]});
    const double d = norm(p - q);
    if (d < best) {
      best = d;
      bt = int(t);
    }
  }
  return {best, bt};
}

struct Scenario {
  formats::Model model;
  SimSetup setup;
  std::vector<Index> bottom, top;
};

// A two-material block (a cut layer boundary) with a muscle, its bottom face sliding over a
// sphere, its top face pulled sideways; damping, hourglass, optionally gravity. `offset` moves the
// whole scene by (offset, offset, offset) m; `materials` are the lower and upper layer's.
Scenario sliding_scenario(int nx, int ny, int nz, bool muscles, bool gravity, double offset = 0,
                          std::vector<formats::Material> materials = {
                              neo_hookean(1000, 0.45, 1000, "soft"),
                              neo_hookean(3000, 0.45, 1000, "firm")}) {
  const double h = 1e-3;
  const double half = 0.5 * nx * h;
  const double radius = 1.5 * nx * h;
  formats::BoxSpec spec;
  spec.dims = {nx, ny, nz};
  spec.voxel_size = h;
  spec.origin = {offset - half, offset - 0.5 * ny * h, offset + radius + 0.5 * h};
  spec.materials = std::move(materials);
  spec.layer_boundaries = {0.55 * nz * h};
  if (muscles) {
    formats::BoxMuscleSpec m;
    m.element_min = {0, 0, nz / 2};
    m.element_max = {nx, ny, nz};
    m.fibre = {1, 0.2, 0};
    m.reference_stress = 2000;
    spec.muscles = {m};
  }
  spec.created = "2026-01-01T00:00:00Z";
  Scenario sc;
  sc.model = formats::make_box_model(spec);
  sc.model.surfaces.push_back(sphere(radius, {offset, offset, offset}, 3));
  sc.bottom = nodes_at(sc.model, 2, 0);
  sc.top = nodes_at(sc.model, 2, nz);
  for (auto n : sc.bottom) {
    const auto [d, t] = surface_distance(sc.model.surfaces[0], sc.model.node_position(n));
    sc.model.sliding.push_back({n, 0, d, t});
  }
  SimSetup& s = sc.setup;
  s.effects.sliding = true;
  s.effects.loads = true;
  s.effects.damping = true;
  s.effects.muscles = muscles;
  s.effects.gravity = gravity;
  s.damping_alpha = 200;
  if (muscles) s.activation = {Curve::ramp(0.02, 1.0)};
  s.prescribed.push_back(
      {sc.top, {true, false, false}, {0.3 * nx * h, 0, 0}, Curve::ramp(0.05, 1.0)});
  return sc;
}

TEST_P(EngineTest, BlockSlidingOverASphereKeepsItsNodesAtRestDistance) {
  auto sc = sliding_scenario(6, 6, 2, false, false);
  auto b = GetParam().make(sc.model, sc.setup);
  const auto& surf = sc.model.surfaces[0];
  double worst = 0;
  int checks = 0;
  const std::int64_t steps = std::int64_t(std::ceil(0.06 / b->dt()));
  for (std::int64_t done = 0; done < steps; done += 50) {
    b->step(50);
    const auto u = b->displacements();
    for (const auto& bind : sc.model.sliding) {
      const auto x = sc.model.node_position(bind.node);
      const auto un = node_u(u, bind.node);
      const auto [d, t] = surface_distance(surf, {x[0] + un[0], x[1] + un[1], x[2] + un[2]});
      worst = std::max(worst, std::abs(d - bind.rest_distance));
      ++checks;
    }
  }
  const auto u = b->displacements();
  double mean_dx = 0;
  for (auto n : sc.bottom) mean_dx += node_u(u, n)[0];
  mean_dx /= double(sc.bottom.size());
  EXPECT_LT(worst, 1e-12);     // m; the sphere has radius 9 mm
  EXPECT_GT(mean_dx, 0.5e-3);  // the bottom really slid (top pulled 1.8 mm)
  std::printf(
      "[ measured ] sliding over a sphere: %d node checks, worst |d − d_rest| = %.3g m, "
      "bottom face moved %.3g mm on average\n",
      checks, worst, mean_dx * 1e3);
}

// A body at rest in float, sliding on, 0.1 m from the origin (the forehead's scale), a stiff
// nearly incompressible layer over a near-fluid one (μ = 1 Pa): float round-off of the absolute
// positions (ε · |x| per step) keeps its nodes moving. That is noise, not an instability: the
// blow-up test must not stop it. With a floor of ε · volume · min modulus alone it stopped at step
// 10 (10^-12 J against a reference of 10^-13 J), as the 0.5 mm forehead at rest did (issue 20).
// The noise stays bounded (measured over 20,000 steps); 2,000 are run here.
TEST_P(EngineTest, BodyAtRestWithSlidingInFloatDoesNotStop) {
  auto sc =
      sliding_scenario(6, 6, 2, false, false, 0.1,
                       {neo_hookean(1, 0.45, 1000, "fat"), neo_hookean(1e5, 0.49, 1000, "skin")});
  sc.setup.effects.loads = false;
  sc.setup.prescribed.clear();
  sc.setup.precision = Precision::float32;
  auto b = GetParam().make(sc.model, sc.setup);
  EXPECT_NO_THROW(b->step(2000));
  const auto e = b->energies();
  EXPECT_LT(e.kinetic, 1e-10);  // J: noise, a few orders below the stop
  std::printf(
      "[ measured ] at rest, sliding, float, 0.1 m from the origin: kinetic %.3g J after "
      "2000 steps of %.3g s\n",
      e.kinetic, b->dt());
}

// The blow-up message's advice fits the cause: after a near-zero reference (a body at rest) it says
// the reference was near zero and suggests double first; after a real reference it says to lower
// the time step. Both keep the wording the stop tests assert ("Lower the time step").
TEST(BlowupMessage, AdviceFitsTheReference) {
  auto sc = sliding_scenario(2, 2, 2, false, false);
  sc.setup.precision = Precision::float32;
  const BackendCore core(sc.model, sc.setup, make_plan(sc.model, sc.setup));
  const auto message = [&](double reference) {
    BackendCore c = core;
    c.set_energy_reference(reference);
    try {
      c.fail_blowup(10, 1.0, 0.0, 0, 1.0);
    } catch (const InstabilityError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const auto at_rest = message(0.0), loaded = message(1e-3);
  EXPECT_NE(at_rest.find("The reference was near zero"), std::string::npos) << at_rest;
  EXPECT_NE(at_rest.find("Lower the time step"), std::string::npos) << at_rest;
  EXPECT_EQ(loaded.find("near zero"), std::string::npos) << loaded;
  EXPECT_NE(loaded.find("Lower the time step (or its safety factor)"), std::string::npos) << loaded;
}

TEST_P(EngineTest, FloatAndDoubleAgreeToFloatPrecision) {
  auto sc = sliding_scenario(6, 6, 3, true, true);
  auto d = GetParam().make(sc.model, sc.setup);
  sc.setup.precision = Precision::float32;
  auto f = GetParam().make(sc.model, sc.setup);
  ASSERT_EQ(d->dt(), f->dt());
  d->step(300);
  f->step(300);
  const auto ud = d->displacements(), uf = f->displacements();
  double diff = 0, umax = 0;
  for (std::size_t i = 0; i < ud.size(); ++i) {
    diff = std::max(diff, std::abs(ud[i] - uf[i]));
    umax = std::max(umax, std::abs(ud[i]));
  }
  const auto ed = d->energies(), ef = f->energies();
  EXPECT_LT(diff / umax, 1e-4);
  EXPECT_LT(std::abs(ed.strain - ef.strain) / ed.strain, 1e-4);
  std::printf(
      "[ measured ] float vs double after 300 steps: max |Δu| / max |u| = %.3g, strain energy "
      "rel. diff %.3g\n",
      diff / umax, std::abs(ed.strain - ef.strain) / ed.strain);
}

TEST_P(EngineTest, ResultsAreBitIdenticalForOneAndTwoThreads) {
  // Large enough that the element, gather and node loops run in parallel (≥ 2048 elements and
  // nodes; smaller loops stay on one thread).
  auto sc = sliding_scenario(24, 24, 4, true, true);
  for (auto precision : {Precision::float64, Precision::float32}) {
    sc.setup.precision = precision;
    sc.setup.threads = 1;
    auto one = GetParam().make(sc.model, sc.setup);
    sc.setup.threads = 2;
    auto two = GetParam().make(sc.model, sc.setup);
    one->step(30);
    two->step(30);
    const auto u1 = one->displacements(), u2 = two->displacements();
    ASSERT_EQ(u1.size(), u2.size());
    EXPECT_EQ(std::memcmp(u1.data(), u2.data(), u1.size() * sizeof(double)), 0);
    const auto e1 = one->energies(), e2 = two->energies();
    EXPECT_EQ(e1.strain, e2.strain);
    EXPECT_EQ(e1.kinetic, e2.kinetic);
    EXPECT_EQ(e1.hourglass, e2.hourglass);
    EXPECT_EQ(e1.external_work, e2.external_work);
    EXPECT_GT(e1.strain, 0.0);
  }
}

TEST_P(EngineTest, RestoreContinuesBitIdentically) {
  auto sc = sliding_scenario(6, 6, 3, true, true);
  for (auto precision : {Precision::float64, Precision::float32}) {
    sc.setup.precision = precision;
    auto a = GetParam().make(sc.model, sc.setup);
    a->step(45);
    const State saved = a->state();
    a->step(55);
    auto b = GetParam().make(sc.model, sc.setup);
    b->restore(saved);
    EXPECT_EQ(b->step_index(), 45);
    b->step(55);
    const auto ua = a->displacements(), ub = b->displacements();
    EXPECT_EQ(std::memcmp(ua.data(), ub.data(), ua.size() * sizeof(double)), 0);
    EXPECT_EQ(a->energies().external_work, b->energies().external_work);
    EXPECT_EQ(a->state().sliding_triangle, b->state().sliding_triangle);
  }
  // A state that does not fit is refused.
  State bad;
  bad.u.resize(3);
  auto c = GetParam().make(sc.model, sc.setup);
  EXPECT_THROW(c->restore(bad), ConfigError);
}

// A damaged checkpoint's state (scripts/fuzz_inputs.py): a sliding triangle id past its surface
// read past the corner array in the first sliding pass; non-finite displacements went into the
// step. Each is refused by name before anything is restored.
TEST_P(EngineTest, RestoreRefusesADamagedState) {
  auto sc = sliding_scenario(6, 6, 3, true, true);
  auto a = GetParam().make(sc.model, sc.setup);
  a->step(10);
  const State good = a->state();
  ASSERT_FALSE(good.sliding_triangle.empty());
  const auto refused = [&](const State& s, const std::string& field) {
    auto b = GetParam().make(sc.model, sc.setup);
    try {
      b->restore(s);
      ADD_FAILURE() << "no error for " << field;
    } catch (const ConfigError& e) {
      EXPECT_EQ(e.field(), field) << e.what();
    }
  };
  for (const std::int32_t t : {-1, 1 << 20, std::numeric_limits<std::int32_t>::max()}) {
    State s = good;
    s.sliding_triangle.back() = t;
    refused(s, "state.sliding_triangle");
  }
  State s = good;
  s.u[4] = std::numeric_limits<double>::quiet_NaN();
  refused(s, "state.u");
  s = good;
  s.u_prev[7] = std::numeric_limits<double>::infinity();
  refused(s, "state.u_prev");
  s = good;
  s.time = std::numeric_limits<double>::quiet_NaN();
  refused(s, "state.time");
  auto b = GetParam().make(sc.model, sc.setup);
  EXPECT_NO_THROW(b->restore(good));
}

TEST_P(EngineTest, ElementFieldsAndDominantMaterial) {
  auto sc = sliding_scenario(6, 6, 3, false, false);
  auto b = GetParam().make(sc.model, sc.setup);
  const auto f0 = b->element_fields();
  for (std::size_t e = 0; e < sc.model.element_count(); ++e) {
    EXPECT_EQ(f0.jacobian[e], 1.0);
    EXPECT_NEAR(f0.von_mises[e], 0.0, 1e-9);
    // The layer boundary is at 1.65 h: elements of the lowest row are soft, the top row firm.
    const int k = sc.model.element_lattice[e][2];
    if (k == 0) {
      EXPECT_EQ(f0.material[e], 0);
    }
    if (k == 2) {
      EXPECT_EQ(f0.material[e], 1);
    }
  }
  b->step(100);
  const auto f1 = b->element_fields();
  double vm = 0, sed = 0;
  for (std::size_t e = 0; e < sc.model.element_count(); ++e) {
    vm = std::max(vm, f1.von_mises[e]);
    sed += f1.energy_density[e] * 1e-9;
    EXPECT_GT(f1.jacobian[e], 0.0);
  }
  EXPECT_GT(vm, 0.0);
  // Σ W V0 equals the strain energy (no muscles here).
  EXPECT_NEAR(sed, b->energies().strain, 1e-9 * sed);
}

INSTANTIATE_TEST_SUITE_P(Backends, EngineTest, ::testing::ValuesIn(kBackends), backend_name);

// ---- Constraint work in the blow-up bound (docs/physics.md, "Instability") --------------------
// On every backend (CUDA cases skip without a device).
class ConstraintWork : public BackendTest<NamedBackend> {};

// The sliding projection's work is the external work's: a bound node thrown at its surface stops
// there in one step (an inelastic impact). Closed form: u(−1) = v Δt n (moving along −n at speed v),
// the free update puts u* = −v Δt n, the projection returns it to 0, so the constraint force is
// m v n / Δt and its work over the step, F · (u(1) − u(−1)) / 2, is −½ m v²: minus the kinetic
// energy the node had. Undamped, unloaded: nothing else does work.
TEST_P(ConstraintWork, SlidingProjectionWorkIsCounted) {
  auto sc = sliding_scenario(4, 4, 2, false, false);
  sc.setup.effects.damping = false;
  sc.setup.effects.loads = false;
  sc.setup.prescribed.clear();
  // The bottom centre node sits straight above the sphere's centre: its normal is +z.
  Index centre = -1;
  for (auto n : sc.bottom) {
    const auto x = sc.model.node_position(n);
    if (std::abs(x[0]) < 1e-12 && std::abs(x[1]) < 1e-12) centre = n;
  }
  ASSERT_GE(centre, 0);
  const double v = 0.2;  // m/s toward the sphere
  sc.setup.initial_velocities.push_back({{centre}, {0, 0, -v}});
  auto b = GetParam().make(sc.model, sc.setup);
  const auto e0 = b->energies();
  ASSERT_GT(e0.kinetic, 0);
  EXPECT_EQ(e0.external_work, 0);
  b->step(1);
  const auto e1 = b->energies();
  EXPECT_NEAR(e1.external_work, -e0.kinetic, 1e-9 * e0.kinetic)
      << "the projection's work over the impact step";
  EXPECT_LT(e1.kinetic, 1e-6 * e0.kinetic);  // the normal motion is gone
  std::printf("[ measured ] %s: node stopped at its surface: KE %.6g J, projection work %.6g J\n",
              GetParam().name.c_str(), e0.kinetic, e1.external_work);
}

// A real blow-up under constraints (sliding over the sphere, the top pulled by a prescribed
// displacement) at the critical estimate h / c_d (above the true limit, physics-notes §4) is caught
// at the same step as before the projections' work entered the bound (step 20, the third energy
// check; measured on the CPU before the change: "kinetic energy blow-up at step 20, t =
// 0.00360375 s: 2.9352e-06 J > 10 × 1.43955e-07 J ...; fastest node 98"), with the same message
// (on the GPU the mirror node, below).
TEST_P(ConstraintWork, BlowUpUnderConstraintsIsStillCaught) {
  auto sc = sliding_scenario(6, 6, 2, false, false);
  const auto probe = make_plan(sc.model, sc.setup);
  sc.setup.time_step.policy = TimeStepPolicy::forced;
  sc.setup.time_step.user_dt = probe.dt_critical;
  auto b = GetParam().make(sc.model, sc.setup);
  std::string message;
  try {
    b->step(2000);
  } catch (const InstabilityError& e) {
    message = e.what();
  }
  std::printf("[ measured ] %s: blow-up under constraints: %s\n", GetParam().name.c_str(),
              message.c_str());
  ASSERT_FALSE(message.empty()) << "no blow-up at the critical estimate";
  EXPECT_NE(message.find("kinetic energy blow-up at step 20, t = 0.00360375 s"), std::string::npos)
      << message;
  // The fastest node: 98 on the CPU; the GPU's last bits (fused multiply-adds) pick its mirror
  // image, node 140 at (−0.003, +0.003, 0.0115), as fast to round-off (measured on an H100).
  const bool cpu = GetParam().name == "cpu";
  EXPECT_TRUE(message.find("fastest node 98 (rest position (-0.003, -0.003, 0.0115) m") !=
                  std::string::npos ||
              (!cpu && message.find("fastest node 140 (rest position (-0.003, 0.003, 0.0115) m") !=
                           std::string::npos))
      << message;
  EXPECT_NE(message.find("Lower the time step"), std::string::npos) << message;
}

INSTANTIATE_TEST_SUITE_P(Backends, ConstraintWork, ::testing::ValuesIn(every_backend()),
                         backend_name);

}  // namespace
}  // namespace sinew::simulator::testing
