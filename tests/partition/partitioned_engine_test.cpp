// The partitioned CPU engine over MPI (docs/multi-gpu.md) against the one-device CPU engine: the
// same bits for the verification scenes on any number of ranks (ctest runs this program under
// `mpirun -n 1`, `-n 2` and `-n 3`). Every rank runs every test; the one-device reference runs on
// each rank too (small models), so each rank checks the whole gathered result.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cstring>

#include "../simulator/engine_test_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/partition/partitioned_engine.hpp"
#include "sinew/simulator/engine/benchmark_models.hpp"
#include "sinew/simulator/engine/cpu_engine.hpp"

namespace sinew::partition {
namespace {

using SimSetup = simulator::Setup;
using simulator::Backend;
using simulator::Curve;
using simulator::Precision;
using simulator::testing::block;
using simulator::testing::make_cantilever;
using simulator::testing::neo_hookean;
using simulator::testing::nodes_at;

int ranks() {
  int n = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &n);
  return n;
}

// Bit equality of two double vectors (NaNs included), the first difference named.
void expect_same_bits(const std::vector<double>& a, const std::vector<double>& b,
                      const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i)
    ASSERT_EQ(0, std::memcmp(&a[i], &b[i], sizeof(double)))
        << what << "[" << i << "]: " << a[i] << " vs " << b[i] << " on " << ranks() << " ranks";
}

// The energies and the external work (loads', prescribed sets', sliding and plane projections'
// and weights' work: docs/physics.md, "Instability").
void expect_same_energies(const simulator::Energies& a, const simulator::Energies& b) {
  expect_same_bits({a.kinetic, a.strain, a.hourglass, a.external_work, a.time},
                   {b.kinetic, b.strain, b.hourglass, b.external_work, b.time}, "energies");
  EXPECT_EQ(a.step, b.step);
}

// Runs both engines `steps` steps in batches and compares state, velocities, energies, forces and
// a reaction after each batch; returns the largest displacement (the scene must move).
double compare(const formats::Model& m, const SimSetup& s, std::int64_t steps, int batches) {
  auto one = simulator::make_cpu_backend(m, s);
  auto parts = make_partitioned_cpu_backend(m, s, MPI_COMM_WORLD);
  EXPECT_EQ(one->dt(), parts->dt());
  expect_same_energies(one->energies(), parts->energies());
  double moved = 0;
  for (int b = 0; b < batches; ++b) {
    one->step(steps / batches);
    parts->step(steps / batches);
    EXPECT_EQ(one->step_index(), parts->step_index());
    const auto u = one->displacements();
    expect_same_bits(u, parts->displacements(), "u(n)");
    expect_same_bits(one->velocities(), parts->velocities(), "v(n)");
    expect_same_energies(one->energies(), parts->energies());
    for (double x : u) moved = std::max(moved, std::abs(x));
  }
  expect_same_bits(one->internal_forces(), parts->internal_forces(), "f");
  const auto r1 = one->reaction(s.rigid_nodes), r2 = parts->reaction(s.rigid_nodes);
  expect_same_bits({r1[0], r1[1], r1[2]}, {r2[0], r2[1], r2[2]}, "reaction");
  const auto f1 = one->element_fields(), f2 = parts->element_fields();
  expect_same_bits(f1.von_mises, f2.von_mises, "von Mises");
  return moved;
}

// The forehead-like slab's brow raise (the CUDA tests' scene): muscles ramping up, damping, the
// y_max edge rigid; with `skull`, its bottom nodes sliding on the curved skull under gravity.
SimSetup forehead_setup(const formats::Model& m, Precision p, bool skull,
                        double activation = 0.05) {
  SimSetup s;
  s.precision = p;
  s.duration = 1;
  s.effects.muscles = true;
  s.effects.damping = true;
  s.effects.sliding = skull;
  s.effects.gravity = skull;
  s.damping_alpha = 200;
  s.activation = {Curve::ramp(2e-3, activation), Curve::ramp(3e-3, activation / 2)};
  for (const auto& ns : m.node_sets)
    if (ns.name == "y_max") s.rigid_nodes = ns.ids;
  return s;
}

class PartitionedEngine : public ::testing::TestWithParam<Precision> {};

// The cantilever of the verification suite (rigid root, tip load ramped by nodal forces, damping,
// hourglass): elasticity, loads with their work, rigid nodes.
TEST_P(PartitionedEngine, CantileverGivesTheOneDeviceBits) {
  auto c = make_cantilever(1000, 0.45, 1000, 1e-3, simulator::HourglassModulus::shear);
  c.setup.precision = GetParam();
  c.setup.duration = 1;
  c.setup.forces[0].curve = Curve::ramp(0.02, 1.0);
  c.setup.forces[0].total[2] *= 1e3;  // large enough to bend visibly in 600 steps
  EXPECT_GT(compare(c.model, c.setup, 600, 3), 1e-6);
}

// A block pulled by a prescribed displacement (constraint work), a sliding plane and a rigid face;
// 3 materials in layers (multi-material rows).
TEST_P(PartitionedEngine, LayeredSkinBlockUnderPrescribedStretchGivesTheOneDeviceBits) {
  const auto m = simulator::make_skin_block_model(18, 6, 5, 0.25e-3);
  SimSetup s;
  s.precision = GetParam();
  s.duration = 1;
  s.effects.loads = true;
  s.effects.damping = true;
  s.damping_alpha = 500;
  s.rigid_nodes = nodes_at(m, 0, 0);
  simulator::PrescribedDisplacement p;
  p.nodes = nodes_at(m, 0, 18);
  p.components = {true, false, false};
  p.value = {0.4e-3, 0, 0};
  p.curve = Curve::ramp(2e-3, 1.0);
  s.prescribed.push_back(p);
  simulator::SlidingPlane plane;
  plane.nodes = nodes_at(m, 2, 0);
  plane.normal = {0, 0, 1};
  s.sliding_planes.push_back(plane);
  EXPECT_GT(compare(m, s, 500, 2), 1e-5);
}

// Muscles: the forehead-like slab (two frontalis boxes, fibres along y), activation ramped, the
// y_max edge rigid, without its sliding skull.
TEST_P(PartitionedEngine, ContractingMusclesGiveTheOneDeviceBits) {
  const auto m = simulator::make_forehead_model(24, 12, 4, 0.5e-3);
  const SimSetup s = forehead_setup(m, GetParam(), false);
  EXPECT_GT(compare(m, s, 400, 2), 1e-7);
}

// Checkpoint and restart: a run cut in two (state → a fresh partitioned engine) ends on the bits
// of the uninterrupted one-device run.
TEST_P(PartitionedEngine, RestartFromItsOwnStateContinuesOnTheSameBits) {
  auto c = make_cantilever(1000, 0.45, 1000, 1e-3, simulator::HourglassModulus::shear);
  c.setup.precision = GetParam();
  c.setup.duration = 1;
  c.setup.forces[0].total[2] *= 1e3;
  auto one = simulator::make_cpu_backend(c.model, c.setup);
  one->step(300);
  auto first = make_partitioned_cpu_backend(c.model, c.setup, MPI_COMM_WORLD);
  first->step(170);
  const auto state = first->state();
  auto second = make_partitioned_cpu_backend(c.model, c.setup, MPI_COMM_WORLD);
  second->restore(state);
  second->step(130);
  expect_same_bits(one->displacements(), second->displacements(), "u after restart");
  expect_same_energies(one->energies(), second->energies());
}

// An unstable run (Δt forced to 3× the critical estimate) stops at the same step with the same
// message on every rank count.
TEST_P(PartitionedEngine, InstabilityStopsAtTheSameStepWithTheSameMessage) {
  const auto m = block(12, 3, 3, 1e-3, neo_hookean(1000, 0.45, 1000));
  SimSetup s;
  s.precision = GetParam();
  s.duration = 1;
  s.rigid_nodes = nodes_at(m, 0, 0);
  s.initial_velocities.push_back({nodes_at(m, 0, 12), {0, 0, -0.01}});
  auto probe = simulator::make_cpu_backend(m, s);
  s.time_step.policy = simulator::TimeStepPolicy::forced;
  s.time_step.user_dt = 3 * probe->plan().dt_critical;
  auto run = [&](Backend& b) -> std::pair<std::int64_t, std::string> {
    try {
      b.step(5000);
    } catch (const InstabilityError& e) {
      return {b.step_index(), e.what()};
    }
    return {b.step_index(), ""};
  };
  auto one = simulator::make_cpu_backend(m, s);
  auto parts = make_partitioned_cpu_backend(m, s, MPI_COMM_WORLD);
  const auto a = run(*one), b = run(*parts);
  ASSERT_FALSE(a.second.empty()) << "the reference run must go unstable";
  EXPECT_EQ(a, b);
  expect_same_bits(one->displacements(), parts->displacements(), "u at the instability");
}

// The forehead-like slab with everything its brow raise uses: muscles, every bottom node sliding
// on the curved skull, gravity, damping, the y_max edge rigid (the CUDA tests' scene).
TEST_P(PartitionedEngine, SlidingContractingForeheadUnderGravityGivesTheOneDeviceBits) {
  const auto m = simulator::make_forehead_model(24, 12, 4, 0.5e-3);
  const SimSetup s = forehead_setup(m, GetParam(), true);
  EXPECT_GT(compare(m, s, 400, 2), 1e-7);
  // Cut in two through a checkpoint: the sliding triangles come from their owners.
  auto one = simulator::make_cpu_backend(m, s);
  one->step(250);
  auto first = make_partitioned_cpu_backend(m, s, MPI_COMM_WORLD);
  first->step(120);
  const auto state = first->state();
  auto second = make_partitioned_cpu_backend(m, s, MPI_COMM_WORLD);
  second->restore(state);
  second->step(130);
  expect_same_bits(one->displacements(), second->displacements(), "u after restart");
  EXPECT_EQ(one->state().sliding_triangle, second->state().sliding_triangle);
}

// Nodes that slide and carry a load or a prescribed displacement: the sliding forehead-like slab,
// bands of its skull nodes pushed into the skull and across it by nodal forces, others pulled
// along y by a prescribed displacement (node layers spread along x, the axis the slabs cut, so
// that on 2 and 3 ranks they lie on several parts). Their programs run force, capture, slide and
// prescribe on their owners, and every kind of work term (forces, prescribed sets, projections,
// weights) enters the external work.
TEST_P(PartitionedEngine, SlidingNodesWithLoadsAndPrescribedDisplacementsGiveTheOneDeviceBits) {
  const auto m = simulator::make_forehead_model(24, 12, 4, 0.5e-3);
  SimSetup s = forehead_setup(m, GetParam(), true);
  s.effects.loads = true;
  auto skull_nodes_at_x = [&](std::initializer_list<int> layers) {
    std::vector<formats::Index> out;
    for (const auto& b : m.sliding)
      for (int x : layers)
        if (m.node_lattice[std::size_t(b.node)][0] == x) out.push_back(b.node);
    return out;
  };
  simulator::NodalForce push;
  push.nodes = skull_nodes_at_x({3, 12, 13});
  push.total = {2e-3, 0, -4e-3};
  push.curve = Curve::ramp(1e-3, 1.0);
  s.forces.push_back(push);
  simulator::PrescribedDisplacement pull;
  pull.nodes = skull_nodes_at_x({8, 9, 20});
  pull.components = {false, true, false};
  pull.value = {0, 0.1e-3, 0};
  pull.curve = Curve::ramp(2e-3, 1.0);
  s.prescribed.push_back(pull);
  EXPECT_GT(compare(m, s, 400, 2), 1e-6);
}

// The 1 mm forehead-like model (63,190 elements, 80,100 nodes: the scale of the demo's 1 mm
// forehead) with its brow-raise effects; the one-device reference runs on rank 0 only, which
// checks the gathered state (every rank's verdict is reduced at exit).
TEST(PartitionedEngineForehead, OneMillimetreBrowRaiseGivesTheOneDeviceBits) {
  const auto m = simulator::make_forehead_model(355, 89, 2, 1e-3);
  SimSetup s = forehead_setup(m, Precision::float64, true, 0.3);
  s.mass_scaling = 36;  // the demo's 1 mm run
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  auto parts = make_partitioned_cpu_backend(m, s, MPI_COMM_WORLD);
  parts->step(60);
  const auto u = parts->displacements();
  const auto e = parts->energies();
  if (rank != 0) return;
  auto one = simulator::make_cpu_backend(m, s);
  one->step(60);
  expect_same_bits(one->displacements(), u, "u(n)");
  expect_same_energies(one->energies(), e);
  double moved = 0;
  for (double x : u) moved = std::max(moved, std::abs(x));
  EXPECT_GT(moved, 1e-8);
}

INSTANTIATE_TEST_SUITE_P(Precisions, PartitionedEngine,
                         ::testing::Values(Precision::float32, Precision::float64),
                         [](const auto& info) {
                           return std::string(info.param == Precision::float32 ? "float"
                                                                               : "double");
                         });

}  // namespace
}  // namespace sinew::partition

// One gtest run per rank; the exit status is non-zero on every rank when any rank failed. Only
// rank 0 prints (the others' output goes to /dev/null unless SINEW_TEST_ALL_RANKS is set).
int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0 && !std::getenv("SINEW_TEST_ALL_RANKS")) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  int failed = RUN_ALL_TESTS() != 0 ? 1 : 0, any = 0;
  MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return any;
}
