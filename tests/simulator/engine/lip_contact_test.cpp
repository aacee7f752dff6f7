// The lips' contact (physics/lip_contact.hpp, Setup::lip_contact) on every backend built: two
// blocks one voxel apart, the upper held at its top, the lower pushed up 1.5 mm into the 1 mm gap.
// With contact the pairs yield by no more than one step's motion under the contact force and the
// upper block is pressed up; without it the lower block passes through. Every backend agrees with
// the CPU.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "engine_test_support.hpp"
#include "sinew/simulator/physics/lip_contact.hpp"

namespace sinew::simulator::testing {
namespace {

const std::vector<NamedBackend>& kBackends = every_backend();

constexpr double kH = 1e-3;       // m
constexpr double kPush = 1.5e-3;  // m, the lower block's rise
constexpr double kRamp = 0.02;    // s
constexpr int kGapLayer = 2;      // the removed layer of voxels (lattice y)

// A block of 4 × 5 × 4 voxels of 1 mm with the layer y ∈ [2, 3] mm removed: the cut.
formats::Model cut_block() {
  const formats::Model full = block(4, 5, 4, kH, neo_hookean(2000, 0.45, 1000));
  formats::Model m;
  m.grid = full.grid;
  m.materials = full.materials;
  m.provenance = full.provenance;
  for (const auto& l : full.element_lattice)
    if (l[1] != kGapLayer) m.element_lattice.push_back(l);
  formats::build_lattice_topology(m);
  for (std::size_t e = 0; e <= m.element_count(); ++e)
    m.material_offsets.push_back(formats::Offset(e));
  m.material_ids.assign(m.element_count(), 0);
  m.material_fractions.assign(m.element_count(), 1.0);
  return m;
}

// The pairs across the cut: the node at y = 3 mm over the node at y = 2 mm, the same (x, z).
std::vector<std::array<Index, 2>> pairs_of(const formats::Model& m) {
  std::vector<std::array<Index, 2>> pairs;
  for (std::size_t u = 0; u < m.node_count(); ++u) {
    if (m.node_lattice[u][1] != kGapLayer + 1) continue;
    for (std::size_t l = 0; l < m.node_count(); ++l) {
      const auto& a = m.node_lattice[u];
      const auto& b = m.node_lattice[l];
      if (b[1] == kGapLayer && a[0] == b[0] && a[2] == b[2]) pairs.push_back({Index(u), Index(l)});
    }
  }
  return pairs;
}

Setup cut_setup(const formats::Model& m, Precision precision, bool contact) {
  Setup s;
  s.precision = precision;
  s.duration = 0.04;
  s.effects.damping = true;
  s.damping_alpha = 100;
  s.effects.loads = true;
  s.effects.contact = contact;
  s.rigid_nodes = nodes_at(m, 1, 5);
  PrescribedDisplacement p;
  p.nodes = nodes_at(m, 1, 0);
  p.value = {0, kPush, 0};
  p.curve = Curve::ramp(kRamp, 1.0);
  p.label = "push";
  s.prescribed.push_back(p);
  if (contact) s.lip_contact = LipContact{pairs_of(m), {0, 1, 0}};
  return s;
}

// The smallest (x_upper − x_lower) · y over the pairs, m.
double min_gap(const formats::Model& m, const std::vector<double>& u) {
  double gap = 1;
  for (const auto& [upper, lower] : pairs_of(m)) {
    const auto pu = m.node_position(upper), pl = m.node_position(lower);
    gap = std::min(gap,
                   pu[1] + u[3 * std::size_t(upper) + 1] - pl[1] - u[3 * std::size_t(lower) + 1]);
  }
  return gap;
}

class LipContactTest : public BackendTest<std::tuple<NamedBackend, Precision>> {};

TEST_P(LipContactTest, TheCutClosesButTheLipsDoNotCross) {
  const auto& [backend, precision] = GetParam();
  const formats::Model m = cut_block();
  ASSERT_EQ(pairs_of(m).size(), 25u);
  auto with = backend.make(m, cut_setup(m, precision, true));
  const std::int64_t steps = with->plan().steps;
  ASSERT_GT(steps, 50);
  // Pressed together, a pair yields by what the contact force moves a node in one step (Δt² F/m,
  // physics/lip_contact.hpp), about 0.1 h × strain here (h = 1 mm; the blocks are compressed by
  // up to 0.25): printed, and bounded by 5% of the voxel.
  double smallest = 1;
  for (std::int64_t k = 0; k < steps; k += 5) {
    with->step(std::min<std::int64_t>(5, steps - k));  // throws on an inverted element
    smallest = std::min(smallest, min_gap(m, with->displacements()));
  }
  std::printf("[ measured ] %s: smallest gap across the cut %.3g mm (Δt %.3g s)\n",
              backend.name.c_str(), 1e3 * smallest, with->dt());
  EXPECT_GT(smallest, -0.05 * kH);
  // The cut closed: the upper block was pressed up by the rest of the push.
  const auto u = with->displacements();
  double rise = 0;
  for (const auto& [upper, lower] : pairs_of(m)) rise += u[3 * std::size_t(upper) + 1] / 25;
  EXPECT_GT(rise, 0.3 * (kPush - kH));  // half of it where both blocks yield alike

  // Without contact the lower block passes through the upper one.
  auto without = backend.make(m, cut_setup(m, precision, false));
  without->step(steps);
  EXPECT_LT(min_gap(m, without->displacements()), -0.5 * (kPush - kH));

  // Every backend agrees with the CPU to its precision's rounding (the tolerance of
  // cuda_backend_test: the GPU's fused multiply-adds round differently).
  if (backend.name != "cpu") {
    auto cpu = make_cpu_backend(m, cut_setup(m, precision, true));
    cpu->step(steps);
    const auto ucpu = cpu->displacements();
    ASSERT_EQ(ucpu.size(), u.size());
    double scale = 0, diff = 0;
    for (std::size_t i = 0; i < u.size(); ++i) {
      scale = std::max(scale, std::abs(ucpu[i]));
      diff = std::max(diff, std::abs(u[i] - ucpu[i]));
    }
    EXPECT_LT(diff, (precision == Precision::float32 ? 1e-3 : 1e-9) * scale);
  }
}

TEST(LipContact, ClosesItsShareOfTheOverlapAndLeavesAGapAlone) {
  using V = Vec3<double>;
  const V up{0, 1, 0};
  // Node 1 mm above its partner at rest, moved 1.5 mm down: overlap 0.5 mm, half closed by it.
  const V v = physics::lip_contact(V{0.1e-3, -1.5e-3, 0}, V{0, 1e-3, 0}, V{0, 0, 0}, up, 0.5);
  EXPECT_NEAR(v[1], -1.25e-3, 1e-15);
  EXPECT_EQ(v[0], 0.1e-3);  // only along the normal
  // The partner held: the whole overlap.
  const V w = physics::lip_contact(V{0, -1.5e-3, 0}, V{0, 1e-3, 0}, V{0, 0, 0}, up, 1.0);
  EXPECT_NEAR(w[1], -1e-3, 1e-15);
  // The lower node (normal −up) under a partner that came down 1.2 mm: overlap 0.2 mm.
  const V l = physics::lip_contact(V{0, 0, 0}, V{0, -1e-3, 0}, V{0, -1.2e-3, 0}, -up, 0.5);
  EXPECT_NEAR(l[1], -0.1e-3, 1e-15);
  // A gap: unchanged, to the bit.
  const V g = physics::lip_contact(V{0, -0.5e-3, 0}, V{0, 1e-3, 0}, V{0, 0, 0}, up, 0.5);
  EXPECT_EQ(g[1], -0.5e-3);
}

std::string case_name(const ::testing::TestParamInfo<std::tuple<NamedBackend, Precision>>& i) {
  return std::get<0>(i.param).name +
         (std::get<1>(i.param) == Precision::float32 ? "_float" : "_double");
}

INSTANTIATE_TEST_SUITE_P(Backends, LipContactTest,
                         ::testing::Combine(::testing::ValuesIn(kBackends),
                                            ::testing::Values(Precision::float32,
                                                              Precision::float64)),
                         case_name);

}  // namespace
}  // namespace sinew::simulator::testing
