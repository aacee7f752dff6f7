// The stop message of an element inverted by its constraints (BackendCore::fail_element,
// constraint_report.hpp), on every backend: deliberately contradictory models invert an element in
// the first steps, and the message names each corner's constraint (sliding surface, rigid set,
// prescribed set) and says the time step is not the cause, instead of advising a smaller one.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "engine_test_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/simulator/engine/constraint_report.hpp"
#include "sinew/simulator/physics/sliding.hpp"

namespace sinew::simulator::testing {
namespace {

using SimSetup = sinew::simulator::Setup;
constexpr double kH = 1e-3;  // m

class ConstraintReport : public BackendTest<NamedBackend> {};

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// Runs up to `steps` steps; the InstabilityError's message and the step it stopped at.
std::string stop_message(Backend& b, std::int64_t steps, std::int64_t& at) {
  try {
    b.step(steps);
  } catch (const InstabilityError& e) {
    at = b.step_index();
    return e.what();
  }
  at = -1;
  return "";
}

// The case, reduced: the bottom nodes of a 3 × 3 × 2 block slide on a plane 0.6 h above
// them (the "floor", outward normal +z), i.e. they lie behind it at rest. The sliding projection
// moves them to 0.6 h above it (z = 1.2 h, above the top of their elements) at the first step.
TEST_P(ConstraintReport, SlidingNodesBehindTheirSurfaceAreNamed) {
  auto model = block(3, 3, 2, kH, neo_hookean(1000, 0.45));
  formats::Surface floor;
  floor.name = "floor";
  floor.role = formats::SurfaceRole::sliding;
  const double z = 0.6 * kH;
  floor.vertices = {{-kH, -kH, z}, {4 * kH, -kH, z}, {4 * kH, 4 * kH, z}, {-kH, 4 * kH, z}};
  floor.triangles = {{0, 1, 2}, {0, 2, 3}};  // counter-clockwise seen from +z
  model.surfaces.push_back(floor);
  for (const Index n : nodes_at(model, 2, 0)) {
    const auto p = model.node_position(n);
    const int t = p[0] - p[1] >= 0 ? 0 : 1;  // the triangle under the node (diagonal x = y)
    model.sliding.push_back({n, 0, z, t});
  }
  SimSetup s;
  s.effects.sliding = true;
  auto b = backend_of(GetParam()).make(model, s);
  std::int64_t at = -1;
  const std::string m = stop_message(*b, 10, at);
  ASSERT_FALSE(m.empty()) << "no stop";
  EXPECT_LE(at, 2) << m;
  EXPECT_TRUE(contains(m, "inverted element (J ≤ 0)")) << m;
  EXPECT_TRUE(contains(m,
                       "sliding on 'floor' (rest distance 0.6 mm; it lay 0.6 mm behind "
                       "(inside) that surface at rest, and the sliding projection moves it out "
                       "to the outer side, 1.2 mm in one step)"))
      << m;
  EXPECT_TRUE(contains(m, "A sliding node lay behind its surface at rest")) << m;
  EXPECT_TRUE(contains(m, "sinew-inspect MODEL --element ")) << m;
  EXPECT_TRUE(contains(m, "a smaller time step will not help")) << m;
  EXPECT_FALSE(contains(m, "Lower the time step")) << m;
  std::printf("[ message ] %s\n", m.c_str());
}

// Contradictory loads: the top of a one-element-thick block is prescribed 2 h down at once while
// its bottom is rigid (the model's rigid nodes). The element inverts at the first step; the message
// names both constraints, the prescribed one by the scene's label.
TEST_P(ConstraintReport, RigidAndPrescribedCornersAreNamed) {
  auto model = block(2, 2, 1, kH, neo_hookean(1000, 0.45));
  model.rigid_nodes = nodes_at(model, 2, 0);
  SimSetup s;
  s.effects.loads = true;
  s.rigid_nodes = model.rigid_nodes;
  PrescribedDisplacement down;
  down.nodes = nodes_at(model, 2, 1);
  down.value = {0, 0, -2 * kH};
  down.label = "boundary[1] (displacement of set 'top')";
  s.prescribed.push_back(down);
  auto b = backend_of(GetParam()).make(model, s);
  std::int64_t at = -1;
  const std::string m = stop_message(*b, 10, at);
  ASSERT_FALSE(m.empty()) << "no stop";
  EXPECT_LE(at, 2) << m;
  EXPECT_TRUE(contains(m, "rigid (the model's rigid nodes)")) << m;
  EXPECT_TRUE(contains(m, "prescribed by boundary[1] (displacement of set 'top')")) << m;
  EXPECT_TRUE(contains(m,
                       "An element inverted within the first 20 steps was inverted by its "
                       "constraints"))
      << m;
  EXPECT_FALSE(contains(m, "Lower the time step")) << m;
  // The same held by the scene instead of the model.
  model.rigid_nodes.clear();
  auto c = backend_of(GetParam()).make(model, s);
  const std::string n = stop_message(*c, 10, at);
  EXPECT_TRUE(contains(n, "rigid (fixed by the scene)")) << n;
}

INSTANTIATE_TEST_SUITE_P(Backends, ConstraintReport, ::testing::ValuesIn(every_backend()),
                         [](const auto& info) { return info.param.name; });

}  // namespace
}  // namespace sinew::simulator::testing
